"""The imgui panel. Changes that alter the rendered image go through the Renderer, which resets
the accumulation; display-only ones (exposure, tone curve) do not reset it."""

import numpy as np

from app.materials import BSDFS
from app.scene.builtin import BUILTIN_SCENES
from app.scene.description import RUSSIAN_ROULETTE
from app.tonemap import TONEMAPS


def _material_editor(imgui, v):
    """The picked shape and its material's parameters, as the registry declares them."""
    shape = v.selected
    table = v.renderer.scene.materials
    m = table.get(shape.material)
    label = table.name_of(shape.material) or f"#{shape.material}"
    imgui.text_wrapped(f"{shape.kind} '{shape.name}': material {label} ({m.type})")
    changed = False
    for param in BSDFS[m.type].params:
        if param.kind == "name":          # resolved into the numbers edited below
            continue
        value = m.params[param.name]
        if param.kind == "color" and param.high == 1.0:
            hit, new = imgui.color_edit3(param.name, np.broadcast_to(value, 3).tolist())
            new = np.clip(new, param.low, param.high)
        elif param.kind == "color":       # a triple beyond [0, 1], such as a conductor's eta
            hit, new = imgui.input_float3(param.name, np.broadcast_to(value, 3).tolist())
            new = np.clip(new, param.low, param.high)
        elif param.kind == "bool":
            hit, new = imgui.checkbox(param.name, bool(value))
        else:
            high = param.high if param.high is not None else 5000.0
            hit, new = imgui.slider_float(param.name, float(value), param.low, high,
                                          flags=imgui.SliderFlags_.logarithmic)
        if hit:
            m.params[param.name], changed = np.asarray(new, np.float64), True
    hit, le = imgui.input_float3("emission", np.asarray(m.emission, np.float64).tolist())
    if hit:
        m.emission, changed = np.maximum(le, 0.0), True
    if changed and BSDFS[m.type].check({k: np.atleast_2d(x) if np.ndim(x) else np.atleast_1d(x)
                                        for k, x in m.params.items()}) is None:
        v.edit_material(shape.material, m)

def draw_panel(v):
    imgui = v.imgui
    r = v.renderer
    imgui.set_next_window_pos((10, 10), imgui.Cond_.first_use_ever)
    imgui.set_next_window_size((330, 0), imgui.Cond_.first_use_ever)
    imgui.begin("pathtrace")
    imgui.text(f"device: {v.backend.device.name[:38]}")
    imgui.text(f"{r.samples} spp   {r.width}x{r.height}{'  (preview)' if v.scale > 1 else ''}")
    imgui.text(f"{v.samples_per_second / 1e6:.1f} Msamples/s   {v.frame_ms:.1f} ms/frame")
    imgui.text(f"display: {v.display_path}")

    if imgui.collapsing_header("Image", imgui.TreeNodeFlags_.default_open):
        _, v.exposure = imgui.slider_float("exposure (EV)", v.exposure, -8.0, 8.0)
        current = TONEMAPS.index(v.tonemap)
        changed, current = imgui.combo("tone curve", current, list(TONEMAPS))
        if changed:
            v.tonemap = TONEMAPS[current]
        s = r.settings
        changed, depth = imgui.slider_int("max depth (0: none)", s.max_depth, 0, 64)
        if changed and (depth > 0 or s.russian_roulette != "off"):
            r.set_settings(max_depth=depth)
        current = RUSSIAN_ROULETTE.index(s.russian_roulette)
        changed, current = imgui.combo("Russian roulette", current, list(RUSSIAN_ROULETTE))
        if changed and (RUSSIAN_ROULETTE[current] != "off" or s.max_depth > 0):
            r.set_settings(russian_roulette=RUSSIAN_ROULETTE[current])
        changed, nee = imgui.checkbox("next-event estimation (MIS)", s.nee)
        if changed:
            r.set_settings(nee=nee)
        env = r.environment
        changed, value = imgui.slider_float("env intensity", env.intensity, 0.0, 10.0)
        if changed:
            env.intensity = value
            r.reset()
        changed, value = imgui.slider_float("env rotation", env.rotation, -180.0, 180.0)
        if changed:
            env.rotation = value
            r.reset()

    if imgui.collapsing_header("Camera", imgui.TreeNodeFlags_.default_open):
        _, v.controls.speed = imgui.slider_float("speed", v.controls.speed, 0.01, 100.0,
                                                 flags=imgui.SliderFlags_.logarithmic)
        changed, fov = imgui.slider_float("vertical fov", r.camera.vfov, 5.0, 120.0)
        if changed:
            r.camera.vfov = fov
            r.reset()
        imgui.text_wrapped("WASD move, Q/E down/up, right mouse look, wheel speed, Shift fast, "
                           "left click picks a sphere, P or F12 screenshot")

    if imgui.collapsing_header("Scene"):
        names = list(BUILTIN_SCENES)
        current = names.index(r.scene.name) if r.scene.name in names else -1
        changed, current = imgui.combo("built-in", current, names)
        if changed:
            v.load_scene(names[current])
        _, v.scene_file = imgui.input_text("file", v.scene_file)
        if imgui.button("open file"):
            v.load_scene(v.scene_file)

    if v.selected is not None and imgui.collapsing_header("Selected", imgui.TreeNodeFlags_.default_open):
        _material_editor(imgui, v)

    if imgui.collapsing_header("Screenshots", imgui.TreeNodeFlags_.default_open):
        changed, folder = imgui.input_text("folder", str(v.screenshot_dir))
        if changed:
            from pathlib import Path
            v.screenshot_dir = Path(folder)
        if imgui.button("screenshot (P)"):
            v.screenshot()
    if v.message:
        imgui.text_wrapped(v.message)
    imgui.end()
