"""The viewer's window and loop. The window never waits for the renderer: each frame polls input,
moves the camera, lets pathtrace.rendering.launches.Progressive collect finished launches and queue new ones
(bands of rows sized to a fraction of a frame), and shows the newest image that has reached the
host (pathtrace.viewer.display, drawn by shaders/display.frag), then the imgui panel. While the
camera rests the image is denoised (pathtrace.io.denoiser) in a worker thread, every time its samples
have doubled. The Viewer's parts: opening.py (scenes opened in the background), denoising.py and
screenshots.py."""

import math
import sys
import threading
import time
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from pathtrace.viewer.display import Display
from pathtrace.errors import UserError
from pathtrace.rendering.launches import Progressive
from pathtrace.rendering.renderer import Renderer
from pathtrace.resources import resource_dir
from pathtrace.viewer.camera_edits import CameraEdits
from pathtrace.viewer.controls import FlyControls, pick_ray
from pathtrace.viewer.denoising import DRAFT_SCALE, Denoising
from pathtrace.viewer.integrators import IntegratorSwitch
from pathtrace.viewer.needs_display import no_display_message, require_display
from pathtrace.viewer.opening import SceneOpening
from pathtrace.viewer.screenshots import Screenshots
from pathtrace.viewer.panel import MARGIN, draw_help, draw_notice, draw_panel

LAUNCH_BUDGET = 1 / 120        # device seconds per launch: a reset waits for at most three
                               # (pathtrace.rendering.launches.QUEUE_AHEAD); larger ones made the 99th-percentile
                               # frame 50-80 ms on two cores
MOVE_BUDGET = 1 / 30           # device seconds for a whole preview pass while the camera moves
MAX_PREVIEW_SCALE = 16         # the coarsest preview: 1/16 of the resolution on each axis
REST_DELAY = 0.1               # seconds without a move before returning to full resolution
UPLOAD_INTERVAL = 0.1          # at rest the noisy image reaches the screen at most this often
                               # (while moving, each preview pass as soon as it is done)
DEFAULT_SIZE = (1280, 720)     # the window's size before its scene is read (fitted to the screen)
FRAME_RATE = 60                # turns of the loop per second at most: the window's work leaves
                               # the rest of the CPU to the renderer (PoCL) and the denoiser
SETTLE = 0.1                   # seconds of redrawing after input, for the panel to answer it
STATUS_INTERVAL = 0.25         # the status line's figures are redrawn at least this often
FRAME_TIMES = 600              # frames whose durations the viewer keeps (frame_times)
SCREEN_FILL = 0.9              # the largest share of the screen a new window takes
DOCKED_SHARE = 1 / 3           # the panel docks beside the image only where the image keeps this
                               # share of the window's width, or loses nothing by it (a portrait
                               # image in a landscape window); elsewhere it starts collapsed and
                               # floats over the image


def fit_window(width: int, height: int, screen: tuple) -> tuple:
    """A window size for a width x height image: the image's own size, scaled down (keeping its
    aspect ratio) to fit SCREEN_FILL of the screen's (w, h) work area."""
    scale = min(1.0, SCREEN_FILL * screen[0] / width, SCREEN_FILL * screen[1] / height)
    return max(int(width * scale), 1), max(int(height * scale), 1)


def image_extent(image: tuple, window: tuple) -> tuple:
    """The share (x, y) of a window that an image fills when shown whole with its aspect ratio,
    centred, the rest bars."""
    ratio = (image[0] / image[1]) / (window[0] / window[1])
    return (1.0, 1.0 / ratio) if ratio > 1 else (ratio, 1.0)


def preview_scale(seconds_per_pixel: float, width: int, height: int) -> int:
    """How much to divide each axis of the image by while the camera moves, so that a pass
    takes about MOVE_BUDGET on the device (Cycles' adaptive resolution)."""
    if seconds_per_pixel is None:
        return 4
    return int(min(max(math.ceil(math.sqrt(seconds_per_pixel * width * height / MOVE_BUDGET)), 1),
                   MAX_PREVIEW_SCALE))


class Viewer(SceneOpening, IntegratorSwitch, Denoising, Screenshots, CameraEdits):
    def __init__(self, backend, scene, screenshot_dir="screenshots", window_size=None, image_size=None):
        """Renders `scene` at its settings' size (pathtrace view --size sets it), in a window of
        window_size (default: that size, fitted to the screen).

        `backend` and `scene` may be functions that return them (pathtrace view passes those):
        the window then opens at a size fitted to image_size, the size the scene will be rendered
        at where it is known before it is read (view --size), else DEFAULT_SIZE, until it is read, and
        stays live, saying what it waits for, while they are called in a worker thread begun
        before it (reading the file, opening the device), the BVH builds and the kernels compile."""
        self.opened_at = time.perf_counter()    # until the first image (SceneOpening.say_first_image)
        self.loading = True           # a scene is being opened (_wait): input that needs the renderer waits
        self.image_size = image_size  # view --size, which scenes opened from the panel take too
        require_display()
        # the scene's opening needs no window: it begins beside the window's (0.3-0.5 s on Xvfb)
        self._begin(lambda: self._start(backend, scene), "opening the scene")
        try:
            screen, fitted = self._open_window(scene, window_size, image_size)
            self._init_display()
        except BaseException:
            self._abandon()
            raise

        self.controls = FlyControls()
        self.exposure, self.tonemap = 0.0, "standard"
        self.screenshot_dir = Path(screenshot_dir)
        self.message, self.error = "", False    # the panel's last line, and whether it is an error
        self.message_fitted = (None, "")          # (message, width, height): the message as its slot shows it (panel.fitted)
        self.error_about = None                 # what that error is about (set_message, clear_error)
        self.scroll_panel_up = False            # the panel scrolled to its top at the next frame
        self.panel_screen = None                # the window's size (points) when the panel was last drawn
        self.scene_file = ""          # the panel's "open file" field
        self.camera_fields = {}       # the camera sliders' last values, by field name (the panel's camera type)
        self.selected = None
        self.show_help = False        # the keyboard help overlay (H)
        self.show_panel = True        # the panel, shown or hidden by Tab
        self.panel_rect = (0, 0, 0, 0)  # where the panel was drawn last (x, y, w, h)
        self.panel_open = False       # whether it was drawn expanded (not collapsed to its title)
        self.notice = ""              # what the window says while there is no image yet
        self.requested_scene = None   # a scene the panel asked for, opened at the next turn
        self.clipped = set()          # labels of widgets the panel could not fit (panel.py)
        self.widgets = {}             # where the panel drew each labelled widget (panel.py)
        self.scale = 1                # the preview's divisor of the resolution (1: full)
        self.draft = False            # resting, at DRAFT_SCALE until its denoised image is shown
        self.opening_preview = False  # the preview is a scene's first image's, not a move's
        self.clean = False            # a denoised image is shown, and the camera has not moved
        self.last_move, self.awaiting_pass = -1.0, False   # awaiting_pass: the last move's preview (frame)
        self.frame_times = deque(maxlen=FRAME_TIMES)   # seconds from one turn's start to the next's
        self.draws = 0                # how many times the window was redrawn
        self._events = 0              # input events so far (the callbacks count them)
        self._redraw_until = self._last_draw = 0.0
        self._last_time, self._cursor = time.perf_counter(), None
        try:
            self.renderer = self._wait()
        except BaseException:
            self._close_window()
            raise
        self._scene_opened(self.renderer.compiled)
        if fitted and callable(scene):
            self.glfw.set_window_size(self.window, *fit_window(self.renderer.width, self.renderer.height, screen))
        self.size = (self.renderer.width, self.renderer.height)    # the full resolution
        self.progressive = Progressive(self.renderer, LAUNCH_BUDGET)
        self.display = Display(self.backend)
        self.denoise = True
        self._denoiser = None
        self._worker = ThreadPoolExecutor(1, thread_name_prefix="denoise")
        self._writer = ThreadPoolExecutor(1, thread_name_prefix="screenshot")
        self._denoiser_lock = threading.Lock()
        self._denoising = None        # (future, resets, samples) of the denoise under way
        self._readback = None         # (event, arrays, resets, samples) read for the denoiser
        self.denoised_at = None       # (resets, samples) of the denoised image shown, or None
        self.denoise_seconds = None   # how long the last denoise took
        self.denoise_error = None
        self._shown = None            # (resets, passes, rows) of the noisy image last requested
        self._new_image, self._last_upload = False, 0.0

    # --- set-up -----------------------------------------------------------------------------
    def _open_window(self, scene, window_size, image_size=None) -> tuple:
        """The window, its OpenGL context and its GUI; (the screen's work area, whether the
        window's size is fitted to the image's)."""
        import glfw
        import moderngl
        from imgui_bundle import imgui
        from imgui_bundle.python_backends.glfw_backend import GlfwRenderer

        self.glfw, self.imgui = glfw, imgui
        if not glfw.init():
            raise UserError(no_display_message())
        monitor = glfw.get_primary_monitor()
        screen = glfw.get_monitor_workarea(monitor)[2:] if monitor else DEFAULT_SIZE
        fitted = window_size is None
        if fitted:
            given = (image_size or DEFAULT_SIZE) if callable(scene) else (scene.settings.width, scene.settings.height)
            window_size = fit_window(*given, screen)
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        title = "pathtrace" if callable(scene) else f"pathtrace - {scene.name}"
        self.window = glfw.create_window(*window_size, title, None, None)
        if not self.window:
            glfw.terminate()
            raise UserError("pathtrace view: could not open an OpenGL 3.3 window on this display")
        glfw.make_context_current(self.window)
        glfw.swap_interval(0)
        self.ctx = moderngl.create_context()
        self.imgui_context = imgui.create_context()
        imgui.set_current_context(self.imgui_context)   # create_context() leaves an existing one current
        imgui.get_io().set_ini_filename("")
        self.gui = GlfwRenderer(self.window)
        self._chain_callbacks()
        return screen, fitted

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
        """How the image reaches the screen. PyPI's pyopencl has no CL/GL sharing, so pathtrace.viewer.display
        copies it through the host."""
        return {"sums": "float sums", "half": "half-float means"}[self.display.mode] + " copied to a texture"

    def _chain_callbacks(self):
        """Our handlers after imgui's; each counts an input event, which asks for redrawing."""
        glfw, gui = self.glfw, self.gui

        def counted(handler):
            def call(window, *args):
                self._events += 1
                handler(window, *args)
            return call

        def on_key(window, key, scancode, action, mods):
            # while text is typed, a character key's press reaches imgui as its character alone
            # (the char callback), unless a modifier makes it a shortcut (Ctrl + A): imgui takes one
            # of a frame's key presses interleaved with characters a frame (its input trickling),
            # so that typing came in at a key a frame, ten a second in a heavy scene's frames
            shortcut = mods & (glfw.MOD_CONTROL | glfw.MOD_ALT | glfw.MOD_SUPER)
            typed = action != glfw.RELEASE and glfw.KEY_SPACE <= key <= glfw.KEY_GRAVE_ACCENT and not shortcut
            if not (typed and self.imgui.get_io().want_text_input):
                gui.keyboard_callback(window, key, scancode, action, mods)
            self.on_key(key, action, mods)

        def on_scroll(window, dx, dy):
            gui.scroll_callback(window, dx, dy)
            if not self._gui_has_mouse():
                self.controls.scroll(dy)

        def on_button(window, button, action, mods):
            gui.mouse_button_callback(window, button, action, mods)
            self.on_mouse_button(button, action, mods)

        glfw.set_key_callback(self.window, counted(on_key))
        glfw.set_scroll_callback(self.window, counted(on_scroll))
        glfw.set_mouse_button_callback(self.window, counted(on_button))
        glfw.set_char_callback(self.window, counted(gui.char_callback))
        glfw.set_cursor_pos_callback(self.window, counted(gui.mouse_callback))
        glfw.set_window_size_callback(self.window, counted(gui.resize_callback))
        glfw.set_window_refresh_callback(self.window, counted(lambda window: None))

    # --- input ------------------------------------------------------------------------------
    def _gui_has_mouse(self) -> bool:
        """Whether the mouse belongs to the panel: imgui says so (as of the last frame), or the
        cursor is over the panel now (an event can arrive before imgui has seen the cursor
        move there)."""
        return self.imgui.get_io().want_capture_mouse or self._cursor_over_panel()

    def _cursor_over_panel(self) -> bool:
        """Whether the cursor is over the panel now, by where the window system says it is
        (imgui keeps the last place it saw inside the window after the cursor has left it)."""
        x, y = self.glfw.get_cursor_pos(self.window)
        px, py, pw, ph = self.panel_rect
        return px <= x < px + pw and py <= y < py + ph

    def key_name(self, key):
        glfw = self.glfw
        names = {glfw.KEY_W: "W", glfw.KEY_A: "A", glfw.KEY_S: "S", glfw.KEY_D: "D", glfw.KEY_Q: "Q",
                 glfw.KEY_E: "E", glfw.KEY_SPACE: "SPACE", glfw.KEY_LEFT_CONTROL: "LEFT_CONTROL"}
        return names.get(key)

    def on_key(self, key, action, mods):
        glfw = self.glfw
        name = self.key_name(key)
        typing = self.imgui.get_io().want_text_input
        # keys go to the panel while the cursor is over it (README), and while a scene opens its
        # worker thread sets the renderer's scene: a screenshot, R or a move then would read a
        # scene half set, or none yet (the first)
        free = not self.imgui.get_io().want_capture_keyboard and not self.loading and not self._cursor_over_panel()
        if action == glfw.PRESS and key in (glfw.KEY_F12, glfw.KEY_P) and not typing and not self.loading:
            self.screenshot()
        elif action == glfw.PRESS and key == glfw.KEY_ESCAPE and not typing:      # (Esc ends an edit)
            glfw.set_window_should_close(self.window, True)
            glfw.hide_window(self.window)      # gone at once, whatever close() then waits for
        elif action == glfw.PRESS and key == glfw.KEY_H and free:
            self.show_help = not self.show_help
        elif action == glfw.PRESS and key == glfw.KEY_TAB and not typing:
            self.show_panel = not self.show_panel
        elif action == glfw.PRESS and key == glfw.KEY_R and free:
            self.reset_camera()
        elif name and action == glfw.PRESS and free:
            self.controls.held.add(name)
        elif name and action == glfw.RELEASE:
            self.controls.held.discard(name)

    def on_mouse_button(self, button, action, mods=0):
        """A left click picks the shape under the cursor; with Ctrl, it focuses the lens there
        instead (focus_at)."""
        glfw = self.glfw
        if self._gui_has_mouse() or self.loading:
            return                                   # a click on the GUI never moves the camera
        if button == glfw.MOUSE_BUTTON_LEFT and action == glfw.PRESS:
            point = self.image_point(*glfw.get_cursor_pos(self.window))
            if point is not None:
                w, h = self.size
                o, d = pick_ray(self.renderer.camera, w, h, *point)
                if mods & glfw.MOD_CONTROL:
                    self.focus_at(o, d)
                else:
                    self.selected = self.renderer.pick(o, d)

    def image_area(self, width: int, height: int) -> tuple:
        """(x0, width) of the part of a window `width` wide (in pixels or points) that the image
        is fitted into: right of the panel where the panel is open and docked at the left edge
        and leaves the image at least a third of the window; the whole window otherwise (the
        panel then floats over the image)."""
        x, _, w, _ = self.panel_rect
        points = self.imgui.get_io().display_size.x or width
        right = (x + w + MARGIN) * width / points
        if self.panel_open and x <= 2 * MARGIN and self.docks(width, height, right):
            return int(right), width - int(right)
        return 0, width

    def docks(self, width: float, height: float, right: float) -> bool:
        """Whether the image, fitted into a window `width` x `height` right of `right`, keeps
        DOCKED_SHARE of the window's width or all it would have without the panel."""
        beside = image_extent(self.size, (max(width - right, 1), height))[0] * (width - right)
        whole = image_extent(self.size, (width, height))[0] * width
        return beside >= min(whole, DOCKED_SHARE * width) - 0.5

    def image_point(self, x: float, y: float):
        """The image pixel (x, y), at full resolution, under window point (x, y); None on the bars
        or the panel."""
        ww, wh = self.glfw.get_window_size(self.window)
        x0, aw = self.image_area(ww, wh)
        ex, ey = image_extent(self.size, (aw, wh))
        u = ((x - x0) / aw - 0.5) / ex + 0.5
        v = (y / wh - 0.5) / ey + 0.5
        if not (0 <= u < 1 and 0 <= v < 1):
            return None
        return u * self.size[0], v * self.size[1]

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
    def clear_error(self, about: str):
        """The error line gone where it is `about` what the user has just changed again (an
        integrator refused for the camera: another integrator or camera type); another error
        stays."""
        if self.error and self.error_about == about:
            self.message, self.error = "", False

    def set_message(self, text: str, error: bool = False, about: str = None):
        """The panel's status line; errors are also printed, for the terminal and its log. `about`:
        what an error is about, for clear_error."""
        self.message, self.error = text, error
        self.error_about = about if error else None
        self.scroll_panel_up = error        # an error at the panel's top, in sight however it was scrolled
        print(f"pathtrace: {text}", file=sys.stderr)

    def _wait(self) -> Renderer:
        """The renderer that the work begun last (SceneOpening._begin) makes, or its exception,
        this thread keeping the window live meanwhile: it draws what the work says it is doing
        (self._status) with the seconds spent, and the title says it too. A window closed
        meanwhile is hidden at once; the work cannot be stopped halfway (a driver's compiler), so
        the close takes effect when it ends. The title then names the scene shown."""
        work = self._work
        self.loading = True
        try:
            while work.thread.is_alive():
                said, fraction = self._status
                waited = time.perf_counter() - work.started
                self.show_progress(said + (f" ({waited:.0f} s)" if waited >= 1 and fraction is None else ""),
                                   fraction)
                if self.glfw.window_should_close(self.window):
                    self.glfw.hide_window(self.window)
                work.thread.join(1 / FRAME_RATE)
        finally:
            work.thread.join()
            self.loading = False
            shown = work.outcome.get("value") or getattr(self, "renderer", None)
            if shown is not None:
                self.glfw.set_window_title(self.window, f"pathtrace - {shown.scene.name}")
        if "error" in work.outcome:
            raise work.outcome["error"]
        return work.outcome["value"]

    def show_progress(self, text: str, fraction: float = None):
        """One frame, outside the loop, that says what the window is busy with (a BVH build,
        the kernels' compilation), with a bar where the fraction done is known; the title says
        it too."""
        glfw, imgui = self.glfw, self.imgui
        self.notice = text
        glfw.set_window_title(self.window, f"pathtrace - {text}" + (f": {fraction:.0%}" if fraction is not None else ""))
        glfw.poll_events()
        self.gui.process_inputs()
        fw, fh = glfw.get_framebuffer_size(self.window)
        # the image shown before, if any (a scene opened from the panel), under the notice, not a
        # blank window; the panel waits, as the work changes the renderer it edits
        self._draw(fw, fh)
        imgui.new_frame()
        draw_notice(self, text, fraction)
        imgui.render()
        self.gui.render(imgui.get_draw_data())
        glfw.swap_buffers(self.window)

    def edit_material(self, index: int, material):
        """Replaces row `index` of the scene's material table (shared by every shape that uses
        it) and resets."""
        self.renderer.scene.materials.set(index, material)
        self.renderer.upload_materials()

    # --- the loop ---------------------------------------------------------------------------
    def frame(self):
        """One turn of the loop. Input is read and the renderer fed every turn; the window is
        redrawn only when there is something new to show (an image, input that the panel may
        answer, or the status line's figures every STATUS_INTERVAL): on a CPU device, drawing
        with Mesa's llvmpipe takes the cores that render."""
        glfw = self.glfw
        glfw.make_context_current(self.window)
        self.imgui.set_current_context(self.imgui_context)
        if self.requested_scene is not None:
            name, self.requested_scene = self.requested_scene, None
            self.load_scene(name)
            self.redraw_soon()
        self.switch_integrator()
        events = self._events
        glfw.poll_events()
        now = time.perf_counter()
        if self._events != events:
            self.redraw_soon()
        # after a move, input is read again once the preview's pass since is shown (its time and
        # the mouse's travel add up meanwhile): read every turn, a move restarted a pass longer
        # than a turn, and nothing was shown until the keys were let go (two cores)
        self.awaiting_pass &= (self._shown or (None,))[0] != self.renderer.resets
        if not self.awaiting_pass:
            dt, self._last_time = now - self._last_time, now
            camera, (dx, dy) = self.renderer.camera, self._mouse_look()
            fast = glfw.get_key(self.window, glfw.KEY_LEFT_SHIFT) == glfw.PRESS
            if self.controls.update(camera, dt, dx, dy, fast):
                self.renderer.set_camera(camera)
                self.last_move, self.awaiting_pass = now, True
        self._set_resolution(self.awaiting_pass or now - self.last_move < REST_DELAY, opening=self.opened_at is not None)
        self.progressive.step()
        new_image = self._update_image(now)
        if new_image or now < self._redraw_until or now - self._last_draw >= STATUS_INTERVAL:
            self._redraw()
            self._last_draw = now
            self.say_first_image(new_image)
        spare = 1 / FRAME_RATE - (time.perf_counter() - now)
        if spare > 0:
            time.sleep(spare)
        self.frame_times.append(time.perf_counter() - now)

    def redraw_soon(self):
        """Asks for the window to be redrawn over the next SETTLE seconds (after a change made
        other than through input, which asks by itself)."""
        self._redraw_until = time.perf_counter() + SETTLE

    def _redraw(self):
        glfw = self.glfw
        self.gui.process_inputs()
        fw, fh = glfw.get_framebuffer_size(self.window)
        if fw > 0 and fh > 0:
            self._draw(fw, fh)
        self.imgui.new_frame()
        if self.show_panel:
            draw_panel(self)
        else:
            self.panel_rect, self.panel_open = (0, 0, 0, 0), False
        if self.texture is None:
            draw_notice(self, f"rendering the first pass of {self.renderer.scene.name}")
        elif self.renderer.building_program or self.requested_integrator:
            kernels = f"the {self.requested_integrator} kernels" if self.requested_integrator else "the kernels"
            draw_notice(self, f"building {kernels} of {self.renderer.scene.name} in the background", bottom=True)
        else:
            self.notice = ""
        if self.show_help:
            draw_help(self)
        self.imgui.render()
        self.gui.render(self.imgui.get_draw_data())
        glfw.swap_buffers(self.window)
        self.draws += 1

    @property
    def resting(self) -> bool:
        """Whether the camera rests: the image is at full resolution, or at the draft's."""
        return self.scale == 1 or self.draft

    def _set_resolution(self, moving: bool, opening: bool = False):
        """Full resolution at rest; while moving, a preview coarse enough for a pass to take
        about MOVE_BUDGET, chosen when the move starts. Where that preview is at least as
        coarse as DRAFT_SCALE and the image is denoised, the camera's coming to rest first renders and
        denoises a draft at DRAFT_SCALE, which is shown until the full resolution's own
        denoised image replaces it: on two cores a clean demo then appears in half the time.
        `opening`: a scene's first image is such a preview too (a fraction of a pass's time),
        followed at once by the full resolution (the denoiser's first start took 5 s there)."""
        if moving or opening:
            if self.resting:
                self.scale = preview_scale(self.progressive.seconds_per_pixel, *self.size)
            self.draft, self.clean, self.opening_preview = False, False, opening and not moving
        elif self.draft:
            drafted = self.denoised_at is not None and self.denoised_at[0] == self.renderer.resets
            if drafted or not self.denoise or self.denoise_error is not None:
                self.scale, self.draft = 1, False
        elif self.scale >= DRAFT_SCALE and self.denoise and self.denoise_error is None and not self.opening_preview:
            self.scale, self.draft = DRAFT_SCALE, True
        else:
            self.scale = 1
        # the denoiser's albedo and normal at rest, while denoising (kept when it is switched
        # off, which then does not restart the image)
        self.renderer.set_aovs(self.resting and (self.denoise or self.renderer.aovs))
        self.renderer.resize(max(self.size[0] // self.scale, 1), max(self.size[1] // self.scale, 1))

    def _update_image(self, now: float) -> bool:
        """Brings the newest image towards the screen, never waiting: the noisy one while it is
        all there is, the denoised one once the camera rests. Returns whether the texture
        changed."""
        r, p = self.renderer, self.progressive
        self._new_image = False
        # both on the CPU, the denoiser would share its cores with the renderer: the renderer
        # pauses while it runs, so that the denoised image comes twice as soon
        p.paused = self._denoising is not None and not self._denoising[0].done() \
            and self._denoiser.device_name == "CPU" and self.backend.device.kind == "CPU"
        self.display.poll(self._upload)
        if self.denoise and self.resting and self._denoiser_ready():
            self._advance_denoise()
        current = (r.resets, p.passes_done, p.rows_done)
        due = not self.resting or now - self._last_upload >= UPLOAD_INTERVAL
        # at rest a denoised image (the draft's, or an earlier one of this view) stays until
        # the next one: a noisy image in between would be a step back
        if p.passes_done >= 1 and current != self._shown and due and not self.display.busy \
                and not (self.denoise and self.clean):
            self.display.request(r.buffer("sum"), r.width, r.height)
            self._shown, self._last_upload = current, now
        return self._new_image

    def _upload(self, pixels: np.ndarray):
        """(H, W, 4) float32 or float16 pixels (radiance in rgb, divided by a) into the display
        texture."""
        self._new_image = True
        h, w, _ = pixels.shape
        dtype = "f2" if pixels.dtype == np.float16 else "f4"
        if self.texture is None or self.texture.size != (w, h) or self.texture.dtype != dtype:
            if self.texture is not None:
                self.texture.release()
            self.texture = self.ctx.texture((w, h), 4, dtype=dtype)
            # clamped, not repeated: scaled with linear filtering, an edge row would otherwise
            # blend in the opposite edge's (a light at the bottom bled into the top row)
            self.texture.repeat_x = self.texture.repeat_y = False
        self.texture.write(np.ascontiguousarray(pixels))

    def _draw(self, fw, fh):
        self.ctx.viewport = (0, 0, fw, fh)
        self.ctx.clear(0.08, 0.08, 0.08)
        if self.texture is None:
            return
        x0, aw = self.image_area(fw, fh)
        self.ctx.viewport = (x0, 0, aw, fh)
        self.texture.use(0)
        self.program["radiance"] = 0
        self.program["exposure"] = self.exposure
        self.program["curve"] = 1 if self.tonemap == "aces" else 0
        self.program["extent"] = image_extent(self.size, (aw, fh))
        self.vao.render(mode=self.ctx.TRIANGLE_STRIP)
        self.ctx.viewport = (0, 0, fw, fh)

    def run(self, frames=None):
        count = 0
        while not self.glfw.window_should_close(self.window) and (frames is None or count < frames):
            self.frame()
            count += 1

    def close(self):
        """Hides the window at once, then lets the work under way end: a denoise in the worker
        (those queued behind it are dropped), the screenshots being written and the launches
        queued on the device."""
        self.glfw.hide_window(self.window)
        self.glfw.poll_events()
        self._worker.shutdown(wait=True, cancel_futures=True)
        self._writer.shutdown(wait=True)          # the screenshots asked for are all written
        if self._denoiser is not None:
            self._denoiser.close()
        self.renderer.finish()
        self._close_window()

    def _close_window(self):
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
