"""The imgui panel, and the keyboard help (H). Changes that alter the rendered image go through
the Renderer, which resets the accumulation; display-only ones (exposure, tone curve) do not.

Every labelled widget shares one width, the panel's less a label column as wide as the widest
label (so no label is ever cut off), and the panel cannot be made narrower than that column
and a usable widget. Text wraps. The panel is resizable, scrolls when its content is taller
than the window, and never leaves the window. Each widget's range holds every value the scene
format accepts."""

from dataclasses import replace
from pathlib import Path

import numpy as np

from pathtrace.cameras import CAMERAS
from pathtrace.compiler.compiled import MAX_RADIANCE
from pathtrace.materials import BSDFS
from pathtrace.materials.bsdf import constant_of
from pathtrace.scene.builtin import BUILTIN_SCENES
from pathtrace.rendering.choices import INTEGRATORS, RUSSIAN_ROULETTE, TONEMAPS
from pathtrace.textures import Texture

MARGIN = 10                 # pixels between the panel and the window's edges
WIDGET_MIN = 150            # the narrowest a widget may get, in pixels
FLOAT_MAX = 3.4e38          # float32's largest value: the kernels' limit for any parameter
INT_MAX = 2**31 - 1
MESSAGE_LINES = 2           # the panel's message slot, in lines
KEYS = (("W A S D", "move"), ("Q / E, Ctrl / Space", "down / up"), ("right mouse drag", "look around"),
        ("mouse wheel", "speed"), ("Shift", "move faster"), ("left click", "pick a shape"),
        ("Ctrl + left click", "focus the lens there"), ("R", "reset the camera to the scene's"),
        ("P or F12", "screenshot (PNG + EXR)"), ("Tab", "hide / show the panel"), ("H", "this help"), ("Esc", "quit"))

# every label the panel draws beside a widget, to size the label column
LABELS = ("exposure (EV)", "tone curve", "max depth (0: none)", "Russian roulette", "env intensity",
          "env rotation", "path queue (0: off)", "speed", "camera type", "built-in", "file", "folder", "emission") + \
    tuple({p.name for bsdf in BSDFS.values() for p in bsdf.params}) + \
    tuple({name.replace("_", " ") for camera in CAMERAS.values() for name in camera.sliders})


# a parameter's name longer than this (principled's sampling rates) goes on a line of its own
# above its widget, rather than widening every row's label column
LABEL_CAP = 22


def _label_column(imgui) -> float:
    return max(imgui.calc_text_size(label).x for label in LABELS if len(label) <= LABEL_CAP) + \
        imgui.get_style().item_inner_spacing.x


class _Layout:
    """Checks, after each labelled widget, that it ended inside the panel (the viewer's
    `clipped` set names those that did not; tests/test_viewer.py asserts it stays empty), and
    notes where it was drawn (the viewer's `widgets`: label -> (x0, y0, x1, y1), window pixels)."""

    def __init__(self, imgui, v):
        self.imgui, self.v = imgui, v
        self.right = imgui.get_cursor_screen_pos().x + imgui.get_content_region_avail().x
        v.clipped, v.widgets = set(), {}

    def check(self, label: str):
        if self._note(label).x > self.right + 0.5:
            self.v.clipped.add(label)

    def _note(self, label: str):
        lo, hi = self.imgui.get_item_rect_min(), self.imgui.get_item_rect_max()
        self.v.widgets[label] = (lo.x, lo.y, hi.x, hi.y)
        return hi

    def header(self, label: str, flags=0) -> bool:
        """A section's header, which spans the panel's whole width by design."""
        opened = self.imgui.collapsing_header(label, flags)
        self._note(label)
        return opened


def _material_editor(imgui, v, layout):
    """The picked shape and its material's parameters, as the registry declares them."""
    shape = v.selected
    table = v.renderer.scene.materials
    m = table.get(shape.material)
    label = table.name_of(shape.material) or f"#{shape.material}"
    imgui.text_wrapped(f"{shape.kind} '{shape.name}': material {label} ({m.type})")
    changed = False
    for param in BSDFS[m.type].params:
        if param.kind == "name" or param.into:     # resolved into the numbers edited below
            continue
        value = m.params[param.name]
        if isinstance(value, Texture):    # named, not edited
            imgui.text_wrapped(f"{param.name}: {texture_label(value)}")
            layout.check(param.name)
            continue
        label = param.name
        if len(label) > LABEL_CAP:
            imgui.text_wrapped(label)
            label = f"##{label}"
        if param.kind == "color" and param.high == 1.0:
            hit, new = imgui.color_edit3(label, np.broadcast_to(value, 3).tolist())
            new = np.clip(new, param.low, param.high)
        elif param.kind == "color":       # a triple beyond [0, 1], such as a conductor's eta
            hit, new = imgui.input_float3(label, np.broadcast_to(value, 3).tolist())
            new = np.clip(new, param.low, param.high)
        elif param.kind == "bool":
            hit, new = imgui.checkbox(label, bool(value))
        else:
            high = param.high if param.high is not None else FLOAT_MAX
            hit, new = imgui.drag_float(label, float(value), max(abs(float(value)), 1e-3) * 0.01,
                                        param.low, high, "%.4g", imgui.SliderFlags_.always_clamp)
        layout.check(param.name)
        if hit:
            m.params[param.name], changed = np.asarray(new, np.float64), True
    if isinstance(m.emission, Texture):
        imgui.text_wrapped(f"emission: {texture_label(m.emission)}")
    else:
        hit, le = imgui.input_float3("emission", np.asarray(m.emission, np.float64).tolist())
        if hit:
            m.emission, changed = np.clip(le, 0.0, MAX_RADIANCE), True
    layout.check("emission")
    bsdf = BSDFS[m.type]
    if changed and bsdf.check({k: np.atleast_2d(x) if np.ndim(x) else np.atleast_1d(x)
                               for k, x in ((k, constant_of(x, bsdf.kind_of(k), Texture.maximum))
                                            for k, x in m.params.items())}) is None:
        v.edit_material(shape.material, m)


def texture_label(texture: Texture) -> str:
    """How the panel names a texture: its name, type and file."""
    name = f"'{texture.name}' " if texture.name else ""
    image = texture.params.get("image")
    source = f" {Path(image.path).name}" if image is not None and image.path else ""
    return f"texture {name}({texture.type}{source})"


def _status(imgui, v):
    """What the device is doing, honest about a pass under way: whole passes, then how far the
    next one is; samples per second as the device measured them."""
    r, p = v.renderer, v.progressive
    times = list(v.frame_times)[-30:]
    frame = sum(times) / max(len(times), 1)
    imgui.text_wrapped(f"scene: {r.scene.name}")
    if r.scene.source:
        imgui.set_item_tooltip(r.scene.source)
    imgui.text_wrapped(f"device: {v.backend.device.name}")
    imgui.set_item_tooltip(f"{v.backend.device.describe()}\ndisplay: {v.display_path}")
    imgui.text_wrapped(f"{1 / max(frame, 1e-6):.0f} fps, {1000 * frame:.1f} ms/frame")
    # short lines, each narrower than the panel whatever its figures, so that none wraps now and
    # then and moves the widgets below it
    imgui.text(f"{p.passes_done} spp + {p.progress:.0%} of the next")
    imgui.text(f"{p.samples_per_second / 1e6:.2f} Msamples/s")
    size = f"{r.width}x{r.height}" + (f" ({'draft' if v.draft else 'preview'} 1/{v.scale} of {v.size[0]}x{v.size[1]})" if v.scale > 1 else "")
    imgui.text_wrapped(size)
    # short lines, and the message in a slot of MESSAGE_LINES lines whether there is one or not,
    # so that nothing below moves as the denoiser starts or stops or a message comes and goes (a
    # click meant for a widget landed on the one that had moved under the cursor); a longer
    # message is cut, whole in its tooltip and in the terminal
    if not v.denoise:
        imgui.text("denoiser: off")
    elif v.denoised_at is not None and v.denoised_at[0] == r.resets and v.resting:
        imgui.text(f"denoised at {v.denoised_at[1]} spp in {v.denoise_seconds:.2f} s")
    else:
        imgui.text("denoiser: waits for a rest")
    # wrapped lines stand a text line apart: the slot holds MESSAGE_LINES of them and no part of the next
    imgui.begin_child("message", (0, MESSAGE_LINES * imgui.get_text_line_height()), imgui.ChildFlags_.none,
                      imgui.WindowFlags_.no_scrollbar | imgui.WindowFlags_.no_scroll_with_mouse)
    if v.message:
        width, height = imgui.get_content_region_avail().x, MESSAGE_LINES * imgui.get_text_line_height_with_spacing()
        key = (("error: " if v.error else "") + v.message, width, height)
        if v.message_fitted[0] != key:       # measured once per message and width, not every frame
            v.message_fitted = key, fitted(key[0], lambda t: imgui.calc_text_size(t, wrap_width=width).y <= height)
        text = v.message_fitted[1]
        if v.error:
            imgui.push_style_color(imgui.Col_.text, (1.0, 0.45, 0.4, 1.0))
        imgui.text_wrapped(text)
        if v.error:
            imgui.pop_style_color()
    imgui.end_child()
    if v.message:
        imgui.set_item_tooltip(("error: " if v.error else "") + v.message)


def fitted(text: str, fits) -> str:
    """`text`, or as many of its first words as fit with " ..." after them (fits(text): whether
    a text fits the message slot), so that a cut message says it is cut: its end, often the
    file's name, is in the tooltip and the terminal."""
    if fits(text):
        return text
    words = text.split(" ")
    while len(words) > 1 and not fits(" ".join(words) + " ..."):
        words.pop()
    return " ".join(words) + " ..."


def draw_panel(v):
    imgui = v.imgui
    r = v.renderer
    io = imgui.get_io()
    column = _label_column(imgui)
    width_min = column + WIDGET_MIN + 2 * imgui.get_style().window_padding.x
    screen_w, screen_h = io.display_size.x, io.display_size.y
    imgui.set_next_window_pos((MARGIN, MARGIN), imgui.Cond_.first_use_ever)
    imgui.set_next_window_size((width_min, screen_h - 2 * MARGIN), imgui.Cond_.first_use_ever)
    # docked at the left, the image beside it (Viewer.image_area); where the image would lose
    # too much of the window to it (a small window, a portrait image), the panel starts as its
    # title bar alone and floats over the image, which takes the window
    imgui.set_next_window_collapsed(not v.docks(screen_w, screen_h, width_min + 2 * MARGIN), imgui.Cond_.first_use_ever)
    # docked at the left edge and open, it follows the window's height as the window is resized
    # (it kept the height of the window it opened in, the image placed beside it)
    x, _, w, h = v.panel_rect
    if v.panel_screen not in (None, (screen_w, screen_h)) and v.panel_open and x <= 2 * MARGIN and h > 0:
        imgui.set_next_window_size((w, screen_h - 2 * MARGIN), imgui.Cond_.always)
    v.panel_screen = (screen_w, screen_h)
    imgui.set_next_window_size_constraints(
        (min(width_min, screen_w - 2 * MARGIN), min(100, screen_h)),
        (max(screen_w - 2 * MARGIN, 1), max(screen_h - 2 * MARGIN, 1)))
    v.panel_open = imgui.begin("pathtrace")[0]
    if v.scroll_panel_up:
        imgui.set_scroll_y(0)
        v.scroll_panel_up = False
    layout = _Layout(imgui, v)
    imgui.push_item_width(-column)
    _status(imgui, v)

    # the picked shape first, in sight in a short window
    if v.selected is not None and layout.header("Selected", imgui.TreeNodeFlags_.default_open):
        _material_editor(imgui, v, layout)

    if layout.header("Image", imgui.TreeNodeFlags_.default_open):
        _, v.exposure = imgui.drag_float("exposure (EV)", v.exposure, 0.02, -100.0, 100.0, "%.2f",
                                         imgui.SliderFlags_.always_clamp)
        layout.check("exposure (EV)")
        changed, current = imgui.combo("tone curve", TONEMAPS.index(v.tonemap), list(TONEMAPS))
        layout.check("tone curve")
        if changed:
            v.tonemap = TONEMAPS[current]
        changed, v.denoise = imgui.checkbox("denoise (Open Image Denoise)", v.denoise)
        layout.check("denoise (Open Image Denoise)")
        if v.denoise_error:
            imgui.text_wrapped(v.denoise_error)
        s = r.settings
        changed, depth = imgui.drag_int("max depth (0: none)", s.max_depth, 0.2, 0, INT_MAX, "%d",
                                        imgui.SliderFlags_.always_clamp)
        layout.check("max depth (0: none)")
        if changed and replace(s, max_depth=depth).paths_end:
            r.set_settings(max_depth=depth)
        current = RUSSIAN_ROULETTE.index(s.russian_roulette)
        changed, current = imgui.combo("Russian roulette", current, list(RUSSIAN_ROULETTE))
        layout.check("Russian roulette")
        if changed and replace(s, russian_roulette=RUSSIAN_ROULETTE[current]).paths_end:
            r.set_settings(russian_roulette=RUSSIAN_ROULETTE[current])
        changed, nee = imgui.checkbox("next-event estimation (MIS)", s.nee)
        layout.check("next-event estimation (MIS)")
        if changed:
            r.set_settings(nee=nee)
        env = r.environment
        most = MAX_RADIANCE / max(float(np.max(env.image)), 1e-30)    # (pathtrace.compiler.compiled)
        changed, value = imgui.drag_float("env intensity", env.intensity, max(env.intensity, 0.01) * 0.01,
                                          0.0, min(most, FLOAT_MAX), "%.4g", imgui.SliderFlags_.always_clamp)
        layout.check("env intensity")
        if changed:
            env.intensity = value
            r.set_environment(env)        # the light table weighs the environment by its power
        changed, value = imgui.slider_float("env rotation", env.rotation % 360.0, 0.0, 360.0, "%.1f deg")
        layout.check("env rotation")
        if changed:
            env.rotation = value % 360.0
            r.reset()
        current = INTEGRATORS.index(v.requested_integrator or s.integrator)
        changed, current = imgui.combo("integrator", current, list(INTEGRATORS))
        layout.check("integrator")
        if changed:
            v.request_integrator(INTEGRATORS[current])

    if layout.header("Camera", imgui.TreeNodeFlags_.default_open):
        _, v.controls.speed = imgui.slider_float("speed", v.controls.speed, 0.01, 1000.0, "%.3g",
                                                 imgui.SliderFlags_.logarithmic)
        layout.check("speed")
        camera = r.camera
        types = list(CAMERAS)
        changed, index = imgui.combo("camera type", types.index(camera.type), types)
        layout.check("camera type")
        if changed:
            camera = v.switch_camera_type(types[index])
        # the sliders of the camera type's own fields (app/cameras/: Camera.sliders)
        for name, (low, high, log) in camera.sliders.items():
            label = name.replace("_", " ")
            changed, value = imgui.slider_float(label, getattr(camera, name), low, high, "%.3g",
                                                imgui.SliderFlags_.logarithmic if log else 0)
            layout.check(label)
            if changed:
                setattr(camera, name, min(max(value, low), high))
                r.set_camera(camera)
        imgui.text_wrapped("H shows the keys; R resets the camera" + ("; Ctrl + left click focuses on the "
                           "surface under the cursor" if hasattr(camera, "focus_distance") else ""))

    if layout.header("Scene", imgui.TreeNodeFlags_.default_open):
        names = list(BUILTIN_SCENES)
        current = names.index(r.scene.name) if r.scene.name in names else -1
        changed, current = imgui.combo("built-in", current, names)
        layout.check("built-in")
        if changed:
            v.requested_scene = names[current]
        # a file, or a built-in scene's name; Enter opens it as the button does
        entered, v.scene_file = imgui.input_text("file", v.scene_file, imgui.InputTextFlags_.enter_returns_true)
        layout.check("file")
        opened = imgui.button("open file")
        layout.check("open file")
        if opened or entered:
            v.requested_scene = v.scene_file

    if layout.header("Speed", imgui.TreeNodeFlags_.default_open):
        changed, queue = imgui.slider_int("path queue (0: off)", r.settings.path_queue, 0, 4)
        layout.check("path queue (0: off)")
        if changed:
            r.set_settings(path_queue=queue)
        imgui.text_wrapped("paths going on past this many vertices wait in a queue: the same image, "
                           "sooner on a GPU where few paths go on long")

    if layout.header("Screenshots", imgui.TreeNodeFlags_.default_open):
        changed, folder = imgui.input_text("folder", str(v.screenshot_dir))
        layout.check("folder")
        if changed:
            from pathlib import Path
            v.screenshot_dir = Path(folder)
        pressed = imgui.button("screenshot (P)")
        layout.check("screenshot (P)")
        if pressed:
            v.screenshot()
    imgui.pop_item_width()
    pos, size = imgui.get_window_pos(), imgui.get_window_size()
    v.panel_rect = (pos.x, pos.y, size.x, size.y)
    imgui.end()


def draw_notice(v, text: str, fraction: float = None, bottom: bool = False):
    """What the window is busy with: while it has no image (a BVH build, the kernels'
    compilation, the first pass), centred over the image's place, with a bar where the fraction done is
    known; with `bottom`, work that goes on behind an image (the scene's own kernels being
    built), at the window's foot, where it hides little of the image."""
    imgui = v.imgui
    io = imgui.get_io()
    x0, width = v.image_area(io.display_size.x, io.display_size.y)    # beside the panel, not under it
    y, pivot = (io.display_size.y - 8, 1.0) if bottom else (io.display_size.y / 2, 0.5)
    imgui.set_next_window_pos((x0 + width / 2, y), imgui.Cond_.always, (0.5, pivot))
    imgui.set_next_window_bg_alpha(0.85)
    flags = (imgui.WindowFlags_.always_auto_resize | imgui.WindowFlags_.no_title_bar
             | imgui.WindowFlags_.no_inputs | imgui.WindowFlags_.no_saved_settings)
    imgui.begin("notice", None, flags)
    # wrapped within the image's place: a long scene name's line ran under a docked panel and
    # past the window's edge
    wrap = max(width - 2 * MARGIN - 2 * imgui.get_style().window_padding.x, 100)
    imgui.push_text_wrap_pos(wrap)
    imgui.text_wrapped(text + ("" if fraction is not None else " ..."))
    imgui.pop_text_wrap_pos()
    if fraction is not None:
        imgui.progress_bar(fraction, (min(max(imgui.calc_text_size(text).x, 200), wrap), 0))
    imgui.end()
    v.notice = text


def draw_help(v):
    """The keyboard help overlay (H), centred in the window."""
    imgui = v.imgui
    io = imgui.get_io()
    imgui.set_next_window_pos((io.display_size.x / 2, io.display_size.y / 2), imgui.Cond_.always, (0.5, 0.5))
    imgui.set_next_window_bg_alpha(0.85)
    flags = imgui.WindowFlags_.always_auto_resize | imgui.WindowFlags_.no_collapse
    opened, v.show_help = imgui.begin("keys (H to close)", v.show_help, flags)
    if opened:
        key_column = max(imgui.calc_text_size(k).x for k, _ in KEYS) + 2 * imgui.get_style().item_spacing.x
        for key, what in KEYS:
            imgui.text(key)
            imgui.same_line(key_column)
            imgui.text(what)
    imgui.end()
