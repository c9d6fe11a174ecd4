"""The viewer in a real X server (Xvfb, Mesa's llvmpipe), driven by real X input events from
xdotool: camera moves reset accumulation, the GUI swallows its clicks, screenshots match a
headless render, resizing works, memory stays flat, and it closes cleanly."""

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from app.image_io import read_hdr
from app.renderer import Renderer
from app.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent
W, H = 640, 360      # the panel covers x < 340; the tests act to its right


@pytest.fixture(scope="module")
def display():
    for tool in ("Xvfb", "xdotool"):
        assert shutil.which(tool), f"{tool} is missing: ./install.sh --dev installs it"
    number = 90 + os.getpid() % 50
    server = subprocess.Popen(["Xvfb", f":{number}", "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    old = os.environ.get("DISPLAY")
    os.environ["DISPLAY"] = f":{number}"
    for _ in range(100):
        if subprocess.run(["xdotool", "getmouselocation"], capture_output=True).returncode == 0:
            break
        time.sleep(0.1)
    yield os.environ["DISPLAY"]
    server.terminate()
    server.wait()
    if old is None:
        del os.environ["DISPLAY"]
    else:
        os.environ["DISPLAY"] = old


@pytest.fixture(scope="module")
def viewer(display, backend, tmp_path_factory):
    from app.viewer.window import Viewer
    v = Viewer(backend, load_scene("simple"), W, H, tmp_path_factory.mktemp("shots"))
    for _ in range(3):
        v.frame()
    yield v
    v.close()


def xdo(*args):
    subprocess.run(["xdotool", *map(str, args)], check=True, capture_output=True)


def window_id(viewer):
    return viewer.glfw.get_x11_window(viewer.window)


def frames(viewer, n):
    for _ in range(n):
        viewer.frame()


def settle(viewer):
    """Lets the camera come to rest and the full resolution return."""
    time.sleep(0.3)
    frames(viewer, 2)


def test_key_moves_the_camera_and_resets_accumulation(viewer):
    settle(viewer)
    frames(viewer, 4)
    before_eye, before_samples = viewer.renderer.camera.eye.copy(), viewer.renderer.samples
    assert before_samples >= 4
    xdo("windowfocus", "--sync", window_id(viewer))
    xdo("keydown", "w")
    viewer.frame()
    after_one_frame = viewer.renderer.samples
    frames(viewer, 4)
    scale_while_moving = viewer.scale
    xdo("keyup", "w")
    frames(viewer, 1)
    eye = viewer.renderer.camera.eye
    forward = viewer.renderer.camera.look_at - eye
    assert np.dot(eye - before_eye, forward) > 0              # W goes forward
    assert after_one_frame == viewer.launch_spp or after_one_frame < before_samples   # reset
    assert scale_while_moving > 1                             # preview resolution while moving
    settle(viewer)
    assert viewer.scale == 1 and (viewer.renderer.width, viewer.renderer.height) == \
        tuple(viewer.glfw.get_framebuffer_size(viewer.window))


def test_right_drag_turns_the_camera(viewer):
    settle(viewer)
    wid = window_id(viewer)
    forward = viewer.renderer.camera.look_at - viewer.renderer.camera.eye
    xdo("mousemove", "--window", wid, 450, 200)
    frames(viewer, 1)
    xdo("mousedown", 3)
    frames(viewer, 1)
    xdo("mousemove", "--window", wid, 500, 200)
    frames(viewer, 2)
    xdo("mouseup", 3)
    frames(viewer, 1)
    after = viewer.renderer.camera.look_at - viewer.renderer.camera.eye
    assert np.degrees(np.arccos(np.dot(forward, after) / np.linalg.norm(forward) / np.linalg.norm(after))) > 2


def test_click_on_the_panel_neither_moves_nor_picks(viewer):
    settle(viewer)
    camera = viewer.renderer.camera.copy()
    viewer.selected = None
    xdo("mousemove", "--window", window_id(viewer), 40, 30)   # inside the panel
    frames(viewer, 2)
    xdo("click", 1)
    frames(viewer, 2)
    assert viewer.selected is None
    np.testing.assert_array_equal(viewer.renderer.camera.eye, camera.eye)


def test_left_click_picks_the_sphere_under_the_cursor(viewer):
    v = viewer
    settle(v)
    v.renderer.set_camera(load_scene("simple").camera)
    settle(v)
    # the blue glossy sphere (scene index 3) lies right of centre, clear of the panel
    xdo("mousemove", "--window", window_id(v), int(W * 0.69), H // 2)
    frames(v, 2)
    xdo("click", 1)
    frames(v, 2)
    assert (v.selected.kind, v.selected.index) == ("sphere", 3)
    samples = v.renderer.samples
    m = v.renderer.scene.materials.get(v.selected.material)
    assert m.type == "phong"
    m.params.update(rho_d=np.array([0.5, 0.1, 0.1]), rho_s=np.array([0.4, 0.4, 0.4]))
    v.edit_material(v.selected.material, m)
    assert v.renderer.samples == 0 and samples > 0           # an edit resets
    np.testing.assert_allclose(v.renderer.compiled.materials["p1"][v.selected.material, :3], 0.4)


def test_left_click_picks_a_mesh_whatever_the_bvh_order(viewer):
    """The Cornell box: a click on the short block names that mesh and its material."""
    v = viewer
    v.load_scene("cornell-box")
    settle(v)
    # the short block stands right of centre, low, clear of the panel
    xdo("mousemove", "--window", window_id(v), int(W * 0.62), int(H * 0.75))
    frames(v, 2)
    xdo("click", 1)
    frames(v, 2)
    assert v.selected is not None
    assert (v.selected.kind, v.selected.name) == ("mesh", "short block")
    assert v.renderer.scene.materials.name_of(v.selected.material) == "white"
    v.load_scene("simple")


def test_a_slow_build_shows_its_progress_in_the_title(viewer, monkeypatch):
    import app.viewer.window as window
    monkeypatch.setattr(window, "PROGRESS_AFTER", 0.0)
    titles = []
    set_title = viewer.glfw.set_window_title
    monkeypatch.setattr(viewer.glfw, "set_window_title", lambda w, t: (titles.append(t), set_title(w, t)))
    viewer.load_scene("spheres8k")
    assert titles[-2] == "pathtrace - building the BVH of spheres8k: 100%"
    assert titles[-1] == "pathtrace - spheres8k" and viewer.renderer.scene.name == "spheres8k"
    viewer.load_scene("simple")


def test_a_scene_that_fails_to_open_leaves_the_viewer_as_it_was(viewer, monkeypatch, capsys):
    import app.viewer.window as window

    def broken(name):
        raise RuntimeError("a library failed")
    monkeypatch.setattr(window, "load_scene", broken)
    before = viewer.renderer.scene.name
    viewer.load_scene("whatever.toml")
    frames(viewer, 2)
    assert viewer.renderer.scene.name == before
    assert viewer.message == "cannot open whatever.toml: RuntimeError: a library failed"
    assert "cannot open whatever.toml" in capsys.readouterr().err


@pytest.mark.parametrize("curve,exposure", [("standard", 0.0), ("aces", 0.5), ("standard", -1.0)])
def test_the_display_shader_matches_tonemap(viewer, curve, exposure):
    """shaders/display.frag (mean = sum / count, exposure, tone curve, sRGB) draws what
    app/tonemap.py writes, to one 8-bit step, on a ramp of radiances from 0 to 4."""
    import moderngl

    from app.tonemap import to_8bit, tonemap
    v = viewer
    radiance = np.stack([np.linspace(0, 4, 64), np.linspace(0, 1, 64), np.linspace(0, 0.05, 64)], -1)[None]
    acc = np.concatenate([radiance * 4, np.full((1, 64, 1), 4.0)], -1).astype(np.float32)   # 4 samples
    texture = v.ctx.texture((64, 1), 4, data=acc.tobytes(), dtype="f4")
    texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
    target = v.ctx.simple_framebuffer((64, 1))
    try:
        target.use()
        v.ctx.viewport = (0, 0, 64, 1)
        texture.use(0)
        v.program["accumulation"] = 0
        v.program["exposure"] = exposure
        v.program["curve"] = 1 if curve == "aces" else 0
        v.vao.render(mode=v.ctx.TRIANGLE_STRIP)
        drawn = np.frombuffer(target.read(components=3), np.uint8).reshape(1, 64, 3)
    finally:
        v.ctx.screen.use()
        texture.release()
        target.release()
    expected = to_8bit(tonemap(radiance, exposure, curve))
    assert np.abs(drawn.astype(int) - expected).max() <= 1


def test_screenshot_matches_a_headless_render(viewer, backend):
    settle(viewer)
    viewer.renderer.reset()
    while viewer.renderer.samples < 32:
        viewer.frame()
    png, exr = viewer.screenshot()
    assert png.exists() and exr.exists() and png.read_bytes()[:4] == b"\x89PNG"
    shot = read_hdr(exr, "screenshot")
    r = viewer.renderer
    headless = Renderer(backend, r.scene.with_settings(**vars(r.settings)), r.width, r.height)
    headless.set_camera(r.camera)
    for _ in range(r.samples):
        headless.add_samples(1)
    headless.finish()
    # the same camera, seed and sample indices: the same samples, summed in another order
    np.testing.assert_allclose(shot, headless.mean(), rtol=1e-4, atol=1e-5)


def test_resize_reallocates_and_resets(viewer):
    settle(viewer)
    viewer.glfw.set_window_size(viewer.window, 480, 270)
    for _ in range(50):
        frames(viewer, 1)
        if viewer.glfw.get_framebuffer_size(viewer.window) == (480, 270):
            break
    settle(viewer)
    assert (viewer.renderer.width, viewer.renderer.height) == (480, 270)
    assert viewer.texture.size == (480, 270)


def rss_mb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def test_many_frames_leave_memory_flat(viewer):
    settle(viewer)
    frames(viewer, 30)
    start = rss_mb()
    for i in range(150):
        if i % 10 == 0:
            viewer.renderer.reset()      # exercise the texture uploads and resets too
        viewer.frame()
    assert rss_mb() - start < 15


@pytest.mark.parametrize("scene", ["simple", str(ROOT / "tests" / "scenes" / "cbox.xml")], ids=["builtin", "mitsuba-xml"])
def test_view_command_closes_cleanly(display, tmp_path, scene):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    r = subprocess.run([sys.executable, "-m", "app", "view", scene, "--size", "160x90", "--frames", "5",
                        "--screenshot", "--screenshot-dir", tmp_path], env=env, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert len(list(tmp_path.glob("*.png"))) == 1 and len(list(tmp_path.glob("*.exr"))) == 1


def test_without_a_display_it_says_how_to_render_headless(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PYTHONPATH"] = str(ROOT)
    r = subprocess.run([sys.executable, "-m", "app", "view"], env=env, capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 1
    assert f"{sys.executable} -m app render simple -o out.png" in r.stderr and "xvfb-run" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
