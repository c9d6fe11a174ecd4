"""The viewer's window and loop. Each frame: poll input, move the camera, add samples through the
core Renderer within a time budget, copy the accumulation buffer to a display texture (through
the host; see `display_path`), draw it with shaders/display.frag, then the imgui panel."""

import datetime
import os
import sys
import time
from pathlib import Path

import numpy as np

from app.errors import UserError
from app.render import next_launch_size
from app.renderer import Renderer
from app.resources import resource_dir
from app.scene import load_scene
from app.viewer.controls import FlyControls, pick_ray
from app.viewer.panel import draw_panel

FRAME_BUDGET = 1 / 40          # seconds of kernel work per frame: keeps the window above 30 fps
PREVIEW_SCALE = 4              # while moving, render at 1/4 of the resolution (as Cycles does)
REST_DELAY = 0.25              # seconds without a move before returning to full resolution
UPLOAD_INTERVAL = 1 / 30       # the host copy to the display texture runs at most this often
PROGRESS_AFTER = 1.0           # seconds before a BVH build shows its progress


def no_display_message() -> str:
    """What to do without a display, with commands that paste as they are: this very program
    (the virtual environment is rarely on PATH) and xvfb-run, or how to install it."""
    import shlex
    import shutil
    program = shlex.quote(sys.argv[0]) if os.path.basename(sys.argv[0]) == "pathtrace" \
        else f"{shlex.quote(sys.executable)} -m app"
    xvfb = f'xvfb-run -s "-screen 0 1280x800x24" {program} view'
    if not shutil.which("xvfb-run"):
        xvfb = f"sudo apt install xvfb, then {xvfb}"
    return (f"pathtrace view needs a display, and none was found. To render headless: "
            f"{program} render simple -o out.png   To run the viewer on a virtual display: {xvfb}")


def require_display():
    """On Linux a window needs an X11 or Wayland display; say so in one line, not a traceback."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise UserError(no_display_message())


class Viewer:
    def __init__(self, backend, scene, width=1280, height=720, screenshot_dir="screenshots"):
        require_display()
        import glfw
        import moderngl
        from imgui_bundle import imgui
        from imgui_bundle.python_backends.glfw_backend import GlfwRenderer

        self.glfw, self.imgui = glfw, imgui
        if not glfw.init():
            raise UserError(no_display_message())
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        self.window = glfw.create_window(width, height, f"pathtrace - {scene.name}", None, None)
        if not self.window:
            glfw.terminate()
            raise UserError("pathtrace view: could not open an OpenGL 3.3 window on this display")
        glfw.make_context_current(self.window)
        glfw.swap_interval(0)
        self.ctx = moderngl.create_context()
        self.imgui_context = imgui.create_context()
        imgui.get_io().set_ini_filename("")
        self.gui = GlfwRenderer(self.window)
        self._chain_callbacks()

        self.backend = backend
        self.controls = FlyControls()
        self.exposure, self.tonemap = 0.0, "standard"
        self.screenshot_dir = Path(screenshot_dir)
        self.message = ""
        self.scene_file = ""          # the panel's "open file" field
        self.selected = None
        self.scale = 1
        self.last_move = -1.0
        self.frame_ms = 0.0
        self.samples_per_second = 0.0
        self.launch_spp = 1
        self._last_upload = 0.0
        self._uploaded_samples = -1
        self._last_time = time.perf_counter()
        self._cursor = None
        fw, fh = glfw.get_framebuffer_size(self.window)
        self.renderer = Renderer(backend, scene, max(fw, 1), max(fh, 1), self._build_progress(scene.name))
        self._init_display()

    # --- set-up -----------------------------------------------------------------------------
    def _init_display(self):
        shaders = resource_dir("shaders")
        self.program = self.ctx.program(vertex_shader=(shaders / "display.vert").read_text(),
                                        fragment_shader=(shaders / "display.frag").read_text())
        quad = np.array([-1, -1, 1, -1, -1, 1, 1, 1], np.float32)
        self.vbo = self.ctx.buffer(quad.tobytes())
        self.vao = self.ctx.vertex_array(self.program, [(self.vbo, "2f", "position")])
        self.texture = None

    @property
    def display_path(self) -> str:
        """How the image reaches the screen. Sharing needs cl_khr_gl_sharing and a pyopencl built
        with GL; where either is missing the accumulation buffer is copied through the host."""
        return "host copy (no CL/GL sharing on this device)"

    def _chain_callbacks(self):
        glfw, gui = self.glfw, self.gui

        def on_key(window, key, scancode, action, mods):
            gui.keyboard_callback(window, key, scancode, action, mods)
            self.on_key(key, action, mods)

        def on_scroll(window, dx, dy):
            gui.scroll_callback(window, dx, dy)
            if not self.imgui.get_io().want_capture_mouse:
                self.controls.scroll(dy)

        def on_button(window, button, action, mods):
            gui.mouse_button_callback(window, button, action, mods)
            self.on_mouse_button(button, action)

        glfw.set_key_callback(self.window, on_key)
        glfw.set_scroll_callback(self.window, on_scroll)
        glfw.set_mouse_button_callback(self.window, on_button)

    # --- input ------------------------------------------------------------------------------
    def key_name(self, key):
        glfw = self.glfw
        names = {glfw.KEY_W: "W", glfw.KEY_A: "A", glfw.KEY_S: "S", glfw.KEY_D: "D", glfw.KEY_Q: "Q",
                 glfw.KEY_E: "E", glfw.KEY_SPACE: "SPACE", glfw.KEY_LEFT_CONTROL: "LEFT_CONTROL"}
        return names.get(key)

    def on_key(self, key, action, mods):
        glfw = self.glfw
        name = self.key_name(key)
        if action == glfw.PRESS and (key in (glfw.KEY_F12, glfw.KEY_P)) and not self.imgui.get_io().want_text_input:
            self.screenshot()
        elif action == glfw.PRESS and key == glfw.KEY_ESCAPE:
            glfw.set_window_should_close(self.window, True)
        elif name and action == glfw.PRESS and not self.imgui.get_io().want_capture_keyboard:
            self.controls.held.add(name)
        elif name and action == glfw.RELEASE:
            self.controls.held.discard(name)

    def on_mouse_button(self, button, action):
        glfw = self.glfw
        if self.imgui.get_io().want_capture_mouse:
            return                                   # a click on the GUI never moves the camera
        if button == glfw.MOUSE_BUTTON_LEFT and action == glfw.PRESS:
            x, y = glfw.get_cursor_pos(self.window)
            w, h = glfw.get_window_size(self.window)
            o, d = pick_ray(self.renderer.camera, w, h, x, y)
            self.selected = self.renderer.pick(o, d)

    def _mouse_look(self):
        glfw = self.glfw
        looking = glfw.get_mouse_button(self.window, glfw.MOUSE_BUTTON_RIGHT) == glfw.PRESS \
            and not self.imgui.get_io().want_capture_mouse
        pos = glfw.get_cursor_pos(self.window)
        delta = (0.0, 0.0)
        if looking and self._cursor is not None:
            delta = (pos[0] - self._cursor[0], pos[1] - self._cursor[1])
        self._cursor = pos if looking else None
        return delta

    # --- what changes the image ------------------------------------------------------------
    def load_scene(self, name: str):
        """Opens a scene; whatever goes wrong is shown in the panel and printed, and the window
        keeps the scene it had."""
        try:
            scene = load_scene(name)
            self.renderer.set_scene(scene, self._build_progress(scene.name))
        except Exception as e:   # a viewer must outlive any bad file, ours or a library's error
            self.message = str(e) if isinstance(e, UserError) else f"cannot open {name}: {type(e).__name__}: {e}"
            print(f"pathtrace: {self.message}", file=sys.stderr)
            return
        self.selected = None
        self.glfw.set_window_title(self.window, f"pathtrace - {scene.name}")
        self.message = f"loaded {scene.name}"

    def _build_progress(self, name: str):
        """A progress callback for a scene's BVH build: once it has taken PROGRESS_AFTER seconds,
        the window's title and a bar across it show how far it is. The bar is drawn with plain
        OpenGL, since the build may run inside the panel's frame."""
        started = time.perf_counter()

        def show(fraction):
            if time.perf_counter() - started < PROGRESS_AFTER:
                return
            self.glfw.set_window_title(self.window, f"pathtrace - building the BVH of {name}: {fraction:.0%}")
            fw, fh = self.glfw.get_framebuffer_size(self.window)
            self.ctx.viewport = (0, 0, fw, fh)
            self.ctx.clear(0.1, 0.1, 0.1)
            self.ctx.clear(0.25, 0.25, 0.25, viewport=(fw // 8, fh // 2 - 6, fw * 3 // 4, 12))
            self.ctx.clear(0.35, 0.6, 0.9, viewport=(fw // 8, fh // 2 - 6, int(fw * 3 // 4 * fraction), 12))
            self.glfw.swap_buffers(self.window)
        return show

    def edit_material(self, index: int, material):
        """Replaces row `index` of the scene's material table (shared by every shape that uses
        it) and resets."""
        self.renderer.scene.materials.set(index, material)
        self.renderer.upload_materials()

    # --- the loop ---------------------------------------------------------------------------
    def frame(self):
        glfw = self.glfw
        glfw.make_context_current(self.window)
        self.imgui.set_current_context(self.imgui_context)
        glfw.poll_events()
        self.gui.process_inputs()
        now = time.perf_counter()
        dt, self._last_time = now - self._last_time, now

        camera = self.renderer.camera
        dx, dy = self._mouse_look()
        fast = glfw.get_key(self.window, glfw.KEY_LEFT_SHIFT) == glfw.PRESS
        if self.controls.update(camera, dt, dx, dy, fast):
            self.renderer.set_camera(camera)
            self.last_move = now
        fw, fh = glfw.get_framebuffer_size(self.window)
        if fw > 0 and fh > 0:
            self.scale = PREVIEW_SCALE if now - self.last_move < REST_DELAY else 1
            self.renderer.resize(max(fw // self.scale, 1), max(fh // self.scale, 1))
            self._render_samples()
            self._draw(fw, fh)
        self.imgui.new_frame()
        draw_panel(self)
        self.imgui.render()
        self.gui.render(self.imgui.get_draw_data())
        glfw.swap_buffers(self.window)
        self.frame_ms = 1000 * (time.perf_counter() - now)

    def _render_samples(self):
        """One launch, sized to take about FRAME_BUDGET seconds."""
        start = time.perf_counter()
        self.renderer.add_samples(self.launch_spp)
        self.renderer.finish()
        elapsed = time.perf_counter() - start
        r = self.renderer
        self.samples_per_second = r.width * r.height * self.launch_spp / max(elapsed, 1e-9)
        self.launch_spp = next_launch_size(self.launch_spp, elapsed, FRAME_BUDGET)

    def _draw(self, fw, fh):
        r = self.renderer
        now = time.perf_counter()
        stale = self.texture is None or self.texture.size != (r.width, r.height)
        if stale or (r.samples != self._uploaded_samples and now - self._last_upload >= UPLOAD_INTERVAL):
            if stale:
                if self.texture is not None:
                    self.texture.release()
                self.texture = self.ctx.texture((r.width, r.height), 4, dtype="f4")
                self._host_copy = np.empty((r.height, r.width, 4), np.float32)
            self.texture.write(r.read_sum(out=self._host_copy))
            self._last_upload, self._uploaded_samples = now, r.samples
        self.ctx.viewport = (0, 0, fw, fh)
        self.ctx.clear(0, 0, 0)
        self.texture.use(0)
        self.program["accumulation"] = 0
        self.program["exposure"] = self.exposure
        self.program["curve"] = 1 if self.tonemap == "aces" else 0
        self.vao.render(mode=self.ctx.TRIANGLE_STRIP)

    def run(self, frames=None):
        count = 0
        while not self.glfw.window_should_close(self.window) and (frames is None or count < frames):
            self.frame()
            count += 1

    def screenshot(self):
        """Writes the displayed image (PNG, tonemapped as shown) and the mean radiance (EXR)."""
        from app.image_io import write_image
        stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S-%f")[:-3]
        base = self.screenshot_dir / f"pathtrace-{self.renderer.scene.name}-{stamp}"
        try:
            self.screenshot_dir.mkdir(parents=True, exist_ok=True)
            image = self.renderer.mean()
            paths = [base.with_suffix(".png"), base.with_suffix(".exr")]
            write_image(paths[0], image, self.exposure, self.tonemap, what="screenshot")
            write_image(paths[1], image, what="screenshot")
        except (UserError, OSError) as e:
            self.message = f"screenshot failed: {e}"
            return None
        self.message = f"saved {paths[0]} and .exr ({self.renderer.samples} spp)"
        print(self.message, file=sys.stderr)
        return paths

    def close(self):
        self.glfw.make_context_current(self.window)
        self.imgui.set_current_context(self.imgui_context)
        self.gui.shutdown()
        if self.texture is not None:
            self.texture.release()
        self.vao.release()
        self.vbo.release()
        self.program.release()
        self.imgui.destroy_context(self.imgui_context)
        self.glfw.destroy_window(self.window)
