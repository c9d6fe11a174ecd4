"""The command line: renders, and one clear message with a non-zero exit for each bad input."""

import os
import re
import shlex
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from pathtrace.errors import UserError
from tests.commands import in_process, pathtrace

ROOT = Path(__file__).resolve().parent.parent


def write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


GOOD = """
[camera]
eye = [0, 1, 5]
look_at = [0, 0, 0]
[environment]
color = 0.5
[[spheres]]
center = [0, 0, 0]
radius = 1
material = { type = "diffuse", rho_d = 0.5 }
"""


def test_render_writes_png_and_exr(tmp_path):
    from pathtrace.io.images import read_hdr
    png, exr = tmp_path / "a.png", tmp_path / "a.exr"
    r = pathtrace("render", "simple", "-o", png, "-o", exr, "--size", "32x18", "--spp", "4", "-q")
    assert r.returncode == 0, r.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    img = read_hdr(exr, "test")
    assert img.shape == (18, 32, 3) and np.all(np.isfinite(img)) and img.max() > 1.0   # HDR kept
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]   # no temporary left


@pytest.mark.parametrize("scene", ["demo", "teapot", "cornell-box"])
def test_a_successful_render_prints_no_warning_from_below(tmp_path, scene):
    """Only our own lines: no RuntimeWarning from NumPy, no line from OpenCV or a driver."""
    r = pathtrace("render", scene, "-o", tmp_path / "a.png", "--size", "16x16", "--spp", "1", "-q")
    assert r.returncode == 0, r.stderr
    assert all(line.startswith(("device: ", "wrote ")) for line in r.stderr.splitlines()), r.stderr


def test_render_denoise_writes_the_denoised_image_the_noisy_layer_and_the_aovs(tmp_path):
    """--denoise: the outputs hold the denoised image and an EXR keeps the noisy one as its layer
    "noisy", which is the image a render without --denoise writes; --aov: the albedo and normal
    beside each output (PNG normals encoded as n / 2 + 1/2)."""
    import OpenEXR
    from pathtrace.io.images import read_hdr
    png, exr, plain = tmp_path / "d.png", tmp_path / "d.exr", tmp_path / "plain.exr"
    common = ("--size", "48x27", "--spp", "4", "-q")
    r = in_process("render", "demo", "-o", png, "-o", exr, "--denoise", "--aov", "albedo,normal", *common)
    assert r.returncode == 0, r.stderr
    assert in_process("render", "demo", "-o", plain, *common).returncode == 0
    with OpenEXR.File(str(exr)) as f:
        channels = f.channels()
        denoised, noisy = channels["RGB"].pixels, channels["noisy"].pixels
    np.testing.assert_allclose(noisy, read_hdr(plain, "test"), rtol=1e-5, atol=1e-6)
    assert np.all(np.isfinite(denoised)) and np.abs(denoised - noisy).mean() > 0.01 * noisy.mean()
    # denoising smooths: neighbouring pixels differ less
    assert np.abs(np.diff(denoised, axis=1)).mean() < 0.5 * np.abs(np.diff(noisy, axis=1)).mean()
    albedo, normal = read_hdr(tmp_path / "d.albedo.exr", "test"), None
    with OpenEXR.File(str(tmp_path / "d.normal.exr")) as f:
        normal = f.channels()["RGB"].pixels
    assert albedo.min() >= 0 and albedo.max() <= 1 and np.abs(normal).max() <= 1 + 1e-5
    for name in ("d.albedo.png", "d.normal.png"):
        assert (tmp_path / name).read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("flag", ["--size", "--spp", "--aov", "--exposure"])
def test_a_huge_or_binary_option_value_is_echoed_short(tmp_path, flag):
    """A value of 100k characters, or one with control characters, is quoted and cut to 60."""
    for value in ("9" * 100_000 + "x", "1\x1b[2J\x07x"):
        r = in_process("render", "simple", "-o", tmp_path / "o.png", flag, value)
        assert r.returncode == 2 and flag in r.stderr and "Traceback" not in r.stderr
        last = r.stderr.strip().splitlines()[-1]
        assert len(last) < 200 and "\x1b" not in last, last


@pytest.mark.parametrize("args", [
    ["render", "simple", "-o", "o.png", "--rr", "q" * 100_000],            # argparse: invalid choice
    ["q" * 100_000],                                                       # an unknown command
    ["render", "simple", "-o", "o.png", "--" + "s" * 100_000],             # unrecognized
    ["render", "simple", "-o", "o.png", "--s=" + "s" * 100_000],           # ambiguous, echoed raw
    ["render", "simple", "-o", "o.png", "--s=a\x1b[2J\x07b"],
    ["render", "simple", "-o", "o.png"] + ["--ab"] * 2_000,            # 8 kB echoed (argparse is quadratic in them)
])
def test_argparses_own_messages_echo_values_short(tmp_path, args):
    r = in_process(*args, cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    last = r.stderr.strip().splitlines()[-1]
    assert "error:" in last and len(last) < 500 and last.isprintable(), last
    assert not list(tmp_path.iterdir())


def test_render_writes_the_depth_the_api_gives_to_hdr_outputs_only(tmp_path):
    """--aov depth: the API's depth (the distance to the first surface) in each channel of an
    HDR file beside the output; a PNG output is refused before rendering, nothing written."""
    from pathtrace import api
    from pathtrace.io.images import read_hdr
    common = ("--size", "24x16", "--spp", "2", "-q")
    r = in_process("render", "cornell-box", "-o", tmp_path / "c.exr", "--aov", "depth", *common)
    assert r.returncode == 0, r.stderr
    depth = read_hdr(tmp_path / "c.depth.exr", "test")
    expected = api.render(api.load("cornell-box"), spp=2, size=(24, 16), aovs=("depth",))["depth"]
    np.testing.assert_allclose(depth, np.repeat(expected[..., None], 3, -1), rtol=1e-6)
    assert (depth > 0).mean() > 0.5               # the box, where camera rays meet it
    r = in_process("render", "cornell-box", "-o", tmp_path / "c.png", "--aov", "depth", *common)
    assert r.returncode == 1 and "--aov depth" in r.stderr.strip().splitlines()[-1]
    assert not (tmp_path / "c.png").exists() and not (tmp_path / "c.depth.png").exists()


def test_an_aov_named_twice_is_written_once():
    from pathtrace.cli.render import _aovs
    assert _aovs("normal, albedo,normal") == ("normal", "albedo")


@pytest.mark.parametrize("value", ["dpth", "albedo,foo", ","])
def test_render_refuses_an_unknown_aov(tmp_path, value):
    r = in_process("render", "simple", "-o", tmp_path / "o.png", "--aov", value)
    assert r.returncode == 2 and "--aov" in r.stderr and "Traceback" not in r.stderr
    assert not list(tmp_path.iterdir())


BAD_FILES = [
    ("[camera\n", "not valid TOML"),
    (GOOD + "\nfoo = 1\n", "unknown key 'foo' (allowed: "),
    (GOOD.replace("rho_d = 0.5 }", "rho_d = 0.5, twosidde = true }"), "unknown key 'twosidde'; did you mean 'twosided'? (allowed: "),
    (GOOD.replace("radius = 1", "radius = -1"), "spheres[0].radius: must be positive, got -1"),
    (GOOD.replace('rho_d = 0.5 }', 'rho_d = 0.5, rho_s = 0.7, n = 10 }').replace('"diffuse"', '"phong"'),
     "rho_d + rho_s must not exceed 1"),
    (GOOD.replace("radius = 1", "radius = nan"), "spheres[0].radius: must be finite"),
    (GOOD.replace("eye = [0, 1, 5]", "eye = [0, inf, 5]"), "camera.eye: must be a list of 3 finite numbers"),
    (GOOD.replace("color = 0.5", 'map = "missing.hdr"'), "environment map"),
    (GOOD.replace('"diffuse"', '"metal"'), "spheres[0].material.type: must be one of"),
    (GOOD.replace("rho_d = 0.5", "rho_d = [0.5, 0.5]"), "must be a number or a list of 3 numbers"),
    (GOOD.replace("[environment]", "[render]\nwidth = 0\n[environment]"), "render.width: must be at least 1"),
    (GOOD.replace("[environment]", "[render]\nrussian_roulette = \"off\"\n[environment]"), "needs a max_depth"),
    # values a float32 or an int32 cannot hold, and shapes of data tomllib or NumPy trip on
    (GOOD.replace("center = [0, 0, 0]", "center = [1e39, 0, 0]"),
     "spheres[0].center: must be a list of 3 finite numbers within float32's range, got [1e+39, 0, 0]"),
    (GOOD.replace("radius = 1", "radius = " + "9" * 400), "spheres[0].radius: must be finite and within float32's range"),
    (GOOD.replace("[environment]", "[render]\nmax_depth = 2147483648\n[environment]"),
     "render.max_depth: must fit in 32 bits, got 2147483648"),
    (GOOD.replace("rho_d = 0.5 }", "rho_d = 0.5, Le = 1e39 }"), "spheres[0].material.Le: must hold finite numbers within float32's range"),
    (GOOD.replace("color = 0.5", "color = 0.5\nintensity = 1e39"), "environment.intensity: must be finite and within float32's range"),
    (GOOD.replace("look_at = [0, 0, 0]", "look_at = [0, 0, 0]\nup = [0, 0, 0]"), "camera.up: must not be zero"),
    (GOOD.replace("color = 0.5", "color = 0.5\nrotation = 1e42"), "environment.rotation: must be finite and within float32's range"),
    (GOOD.replace("look_at = [0, 0, 0]", "look_at = [0, 0, 0]\nup = [1e-320, 0, 0]"), "camera.up: must not be zero"),
    (GOOD + "\nx = " + "[" * 1000 + "]" * 1000 + "\n", "nested too deeply"),
    (GOOD.replace('type = "diffuse"', 'type = ["diffuse"]'), "spheres[0].material.type: must be one of"),
    (GOOD.replace('material = { type = "diffuse", rho_d = 0.5 }', 'material = { type = {} }'), "spheres[0].material.type: must be one of"),
    # a string where a texture may stand is a texture's name; a material is a name or a table
    (GOOD.replace("rho_d = 0.5 }", 'rho_d = 0.5, Le = "glow" }'), "spheres[0].material.Le: no texture named 'glow'"),
    (GOOD.replace('material = { type = "diffuse", rho_d = 0.5 }', "material = 3"),
     "spheres[0].material: must be a material's name or a table, got 3"),
]


@pytest.mark.parametrize("text,message", BAD_FILES)
def test_bad_scene_file_gets_one_clear_message(tmp_path, text, message):
    scene = write(tmp_path, text)
    out = tmp_path / "out.png"
    r = in_process("render", scene, "-o", out, "--spp", "1", "--size", "8x8")
    assert r.returncode != 0
    assert message in r.stderr and str(scene) in r.stderr, r.stderr
    assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_a_huge_environment_rotation_wraps(tmp_path):
    """A rotation near float32's limit (1e42, beyond it, crashed the kernel; it is refused now):
    the angle is wrapped to [0, 360) in float64 before it reaches the device."""
    from pathtrace.io.images import read_hdr
    scene = write(tmp_path, GOOD.replace("color = 0.5", 'map = "studio_small_03_1k.hdr"\nrotation = 3e38'))
    out = tmp_path / "o.exr"
    r = in_process("render", scene, "-o", out, "--spp", "2", "--size", "16x8", "-q")
    assert r.returncode == 0, r.stderr
    assert np.all(np.isfinite(read_hdr(out, "test")))


@pytest.mark.parametrize("name,data", [("broken.hdr", b"not an image"), ("broken.hdr", b""),
                                       ("broken.pfm", b""), ("broken.exr", b""), ("broken.exr", b"\x76\x2f\x31\x01")])
def test_unreadable_environment_map(tmp_path, name, data):
    """Garbage, an empty file (OpenCV's decoder failed an assertion on it) or a bare header."""
    (tmp_path / name).write_bytes(data)
    scene = write(tmp_path, GOOD.replace("color = 0.5", f'map = "{name}"'))
    r = in_process("render", scene, "-o", tmp_path / "o.png", "--spp", "1")
    assert r.returncode == 1 and r.stderr.count("\n") == 1, r.stderr
    assert "environment.map: '" in r.stderr and f"{name}' is not a readable HDR image" in r.stderr



def test_a_missing_scene_files_near_name_is_of_its_folder_compared_without_extensions(tmp_path):
    """The nearest scene file of a missing one's folder is offered where their names are close
    without their extensions: not the folder's only scene file for any name ending alike."""
    (tmp_path / "typo.xml").write_text("<scene/>")
    for name, suggested in (("typ.xml", True), ("typo.xm", True), ("nope.xml", False)):
        r = in_process("render", tmp_path / name, "-o", tmp_path / "o.png")
        assert r.returncode != 0 and "does not exist" in r.stderr, r.stderr
        assert ("did you mean 'typo.xml'?" in r.stderr) == suggested, (name, r.stderr)


@pytest.mark.parametrize("args,message", [
    (["missing.toml"], "error: scene file 'missing.toml' does not exist\n"),
    (["missing.xml"], "error: scene file 'missing.xml' does not exist\n"),
    (["missing.pbrt"], "error: scene file 'missing.pbrt' does not exist\n"),
    (["nosuchscene"], "neither a scene file nor a built-in scene (built-ins: simple,"),
    (["cornel-box"], "cornel-box: neither a scene file nor a built-in scene; did you mean cornell-box? (built-ins: "),
    # a name written as a file's path is a file that is not there, with its folder's nearest scene file
    (["./tests/scenes/cbox.xm"], "/cbox.xm' does not exist; did you mean 'cbox.xml'?\n"),
    # of the files of that name, the nearest whole name (cbox.pbrt and cbox.xml lie there)
    (["./tests/scenes/cbox.pbrt.gz"], "/cbox.pbrt.gz' does not exist; did you mean 'cbox.pbrt'?\n"),
    (["nowhere/cornell-box"], "error: scene file 'nowhere/cornell-box' does not exist\n"),
    (["simple", "--tonemap", "acse"], "invalid choice: 'acse' (choose from 'standard', 'aces'); did you mean aces? "
                                      "(see 'pathtrace render -h')\n"),
    (["simple", "--filter", "gausian:2"], "invalid choice: 'gausian' (choose from 'box', 'tent', 'gaussian'); did you "
                                          "mean gaussian? (see 'pathtrace render -h')\n"),
    (["README.md"], "README.md: not a scene file: pathtrace reads .toml (its own format), .xml (Mitsuba 3) and .pbrt or "
                    ".pbrt.gz (pbrt-v4)\n"),
    (["simple", "--sppp", "4"], "unrecognized arguments: --sppp 4; did you mean --spp? (see 'pathtrace render -h')\n"),
    (["simple", "--rr=throughput", "--max-deph", "4"], "unrecognized arguments: --max-deph 4; did you mean --max-depth? "
                                                     "(see 'pathtrace render -h')\n"),
    (["simple", "--device", "no-such-device"], "error: device: no OpenCL device matches 'no-such-device'"),
    (["simple", "--device", ""], "error: device: empty; give auto, gpu, cpu"),
    (["simple", "--size", "0x10"], "width and height must be 1 to 16384"),
    (["simple", "--size", "-64x48"], "argument --size: '-64x48': width and height must be 1 to 16384"),
    (["simple", "--size", "big"], "is not WIDTHxHEIGHT"),
    (["simple", "--spp", "0"], "out of range"),
    (["simple", "--spp", "many"], "is not an integer"),
    (["simple", "--rr", "off"], "--rr off needs --max-depth"),
    (["simple", "--exposure", "nan"], "is not a finite number"),
    (["simple", "--max-depth", "2147483648"], "2147483648 is out of range (must be 0 to 2147483647)"),
    (["simple", "--spp", "2147483648"], "2147483648 is out of range (must be 1 to 2147483647)"),
    (["simple", "--path-queue", "-1"], "-1 is out of range (must be 0 to 64); or auto"),
    (["simple", "--path-queue", "automatic"], "'automatic' is not an integer; or auto"),
])
def test_bad_arguments_get_one_clear_message(tmp_path, args, message):
    out = tmp_path / "o.png"
    r = in_process("render", *args, "-o", out)
    assert r.returncode != 0 and message in r.stderr, r.stderr
    assert "Traceback" not in r.stderr
    assert not out.exists()


def test_values_that_start_with_a_minus_are_the_options_values():
    """'-.5' and '-2e1' are numbers, and '-64x48' a size its type refuses (test above): none is
    taken for an option."""
    from pathtrace.cli.main import build_parser
    args = build_parser().parse_args(["render", "simple", "-o", "x.png", "--exposure", "-.5"])
    assert args.exposure == -0.5
    args = build_parser().parse_args(["farm", "render", "simple", "-o", "x.png", "--orbit", "-2e1"])
    assert args.orbit == -20.0


@pytest.mark.parametrize("name", ["no\nsuch\nscene", "no\x1b[31msuch", "x" * 5000])
def test_a_scene_name_that_does_not_print_is_shown_on_one_line(tmp_path, name):
    """A name with a newline or an escape sequence, or one too long for the file system, is
    shown escaped and cut, in one line."""
    r = in_process("render", name, "-o", tmp_path / "o.png")
    assert r.returncode == 1 and r.stderr.count("\n") == 1 and "\x1b" not in r.stderr, r.stderr
    assert len(r.stderr) < 400 and "Traceback" not in r.stderr


@pytest.mark.parametrize("output,message", [
    ("nofolder/o.png", "folder 'nofolder' does not exist"),
    ("o.tiff", "unknown image format"),
    ("outdir/", "'outdir/' is a folder; give an image file's name, such as outdir/image.png"),
    ("", "'' is empty; give an image file's name, such as image.png"),
    ("a\nb/", "'a\\nb/' is a folder; give an image file's name, such as a\\nb/image.png"),   # one line
])
def test_bad_output_fails_before_rendering(tmp_path, output, message):
    (tmp_path / "outdir").mkdir()
    r = in_process("render", "simple", "-o", tmp_path / output if output and "/" not in output else output, "--spp", "1",
                  cwd=tmp_path)
    assert r.returncode == 1 and message in r.stderr and r.stderr.count("\n") == 1, r.stderr


def test_unwritable_output_folder(tmp_path):
    if os.geteuid() == 0:
        out = Path("/proc/o.png")     # root may write anywhere else
    else:
        folder = tmp_path / "ro"
        folder.mkdir(mode=0o500)
        out = folder / "o.png"
    r = in_process("render", "simple", "-o", out, "--spp", "1", "--size", "8x8")
    assert r.returncode == 1 and "not writable" in r.stderr, r.stderr


def test_devices_lists_the_cpu():
    r = in_process("devices", "--check")
    assert r.returncode == 0 and "builds the generic kernels" in r.stdout, r.stdout + r.stderr


def test_the_checks_bvh_builds_leave_every_builder_kernel_compiled_for_pocl(tmp_path):
    """devices --check builds two trees (warm_builder) so that a user's first new scene's tree
    waits for none of PoCL's compiles: each of the builder's kernels, for a small grid and a
    large one, is in a fresh PoCL cache afterwards."""
    code = ("from pathtrace.cli.listing import warm_builder; from pathtrace.device.opencl import choose_device; "
            "warm_builder(choose_device('cpu', log=lambda line: None))")
    env = {**os.environ, "POCL_CACHE_DIR": str(tmp_path / "pocl"), "XDG_CACHE_HOME": str(tmp_path / "xdg")}
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True, capture_output=True)
    kernels = [k for k in (tmp_path / "pocl").glob("*/*/*") if k.is_dir()]
    built = {(k.name, "smallgrid" in v.name) for k in kernels for v in k.iterdir()}
    names = {m for f in (ROOT / "kernels" / "build").glob("*.cl")
             for m in re.findall(r"^kernel void (\w+)", f.read_text(), re.M)}
    assert len(names) >= 10
    assert {(name, small) for name in names for small in (False, True)} <= built, sorted(built)


def test_a_bvh_builder_that_fails_in_the_check_is_named_in_one_line(monkeypatch):
    import pyopencl as cl
    import pathtrace.compiler.bvh as bvh

    def failing(*args, **kwargs):
        raise cl.MemoryError("clEnqueueNDRangeKernel failed: OUT_OF_RESOURCES")
    monkeypatch.setattr(bvh, "build_bvh", failing)
    r = in_process("devices", "--check")
    assert r.returncode == 0 and "renders with them" in r.stdout, r.stdout + r.stderr
    assert "; cannot build the BVH builder: clEnqueueNDRangeKernel failed: OUT_OF_RESOURCES" in r.stdout
    assert "cannot build the kernels" not in r.stdout and "Traceback" not in r.stderr


def test_devices_check_fails_where_no_device_builds_the_kernels(monkeypatch):
    """`devices --check` where no device builds the kernels: each device's line says why, and the
    status is 1 with one line more, which install.sh reports ("no OpenCL device builds the kernels
    yet"), not 0 for a set-up that renders nothing."""
    import pyopencl as cl
    import pathtrace.device.opencl as opencl

    def failing(*args, **kwargs):
        raise cl.RuntimeError("clBuildProgram failed: BUILD_PROGRAM_FAILURE")
    monkeypatch.setattr(opencl, "open_device", failing)
    r = in_process("devices", "--check")
    assert r.returncode == 1 and "cannot build the kernels: " in r.stdout, r.stdout + r.stderr
    assert r.stderr.splitlines()[-1] == "pathtrace: error: no OpenCL device here builds the kernels (the lines above say why)"


def test_ctrl_c_stops_cleanly_and_writes_nothing(tmp_path):
    import signal
    import time
    out = tmp_path / "o.png"
    p = subprocess.Popen([sys.executable, "-m", "pathtrace", "render", "spheres8k", "-o", str(out),
                          "--spp", "100000", "--size", "64x36"], cwd=ROOT,
                         stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    line = ""
    while "spp" not in line and time.time() < deadline:   # wait until rendering has begun
        line = p.stderr.readline()
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130 and "nothing written" in err and "Traceback" not in err, err
    # on a line of its own, after the progress bar's (split at newlines only: a bar redraws with \r)
    assert any(line.startswith("pathtrace: interrupted at ") for line in err.split("\n")), err
    assert not out.exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize("quiet", [False, True])
def test_an_interrupted_render_says_how_far_it_got(monkeypatch, tmp_path, quiet):
    """The interrupt's line counts the samples done, with -q too (whose disabled bar counts none)."""
    import pathtrace.api as api

    def render(scene, progress=None, **kwargs):
        progress(7)
        raise KeyboardInterrupt
    monkeypatch.setattr(api, "render", render)
    r = in_process("render", "simple", "--spp", "100", "--size", "16x9", "-o", tmp_path / "o.png", *["-q"] * quiet)
    assert r.returncode == 130 and "pathtrace: interrupted at 7/100 spp; nothing written" in r.stderr, r.stderr
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("module", ["numpy", "pyopencl", "pathtrace.cli.main"])
def test_ctrl_c_while_the_package_imports_gets_one_line(tmp_path, module):
    """SIGINT sent as the console entry point starts importing `module` (an audit hook fires at
    that moment, so the test hits the window every time; a real Ctrl-C there is a matter of
    luck). Once, as one Ctrl-C: the devices open in a thread of their own (api.DevicesOpening),
    which may import PyOpenCL at the same time as the main thread, each import firing the hook."""
    child = f"""
import os, signal, sys
sent = []
def hook(event, args):
    if event == "import" and args[0] == {module!r} and not sent:
        sent.append(True)
        os.kill(os.getpid(), signal.SIGINT)
sys.addaudithook(hook)
sys.argv = ["pathtrace", "render", "simple", "-o", {str(tmp_path / "o.png")!r}]
from pathtrace.cli.console import run
run()
"""
    r = subprocess.run([sys.executable, "-c", child], cwd=ROOT,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 130 and r.stderr == "pathtrace: interrupted\n", r.stderr
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("users", [None, "2"])
def test_the_console_loads_numpy_with_one_blas_thread(users):
    """The entry point loads NumPy's OpenBLAS with one thread, where it would start one per core,
    and leaves OPENBLAS_NUM_THREADS as it found it, for the programs a command starts; a user's
    own setting stands."""
    child = ("import os; from pathtrace.cli.console import _numpy_on_one_blas_thread as load; load(); "
             "print(len(os.listdir('/proc/self/task')), os.environ.get('OPENBLAS_NUM_THREADS'))")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if users:
        env["OPENBLAS_NUM_THREADS"] = users
    r = subprocess.run([sys.executable, "-c", child], cwd=ROOT, capture_output=True, text=True, env=env, timeout=60)
    threads, variable = r.stdout.split()
    if users:
        assert variable == users and (os.cpu_count() < 2 or int(threads) > 1), r.stdout
    else:
        assert (int(threads), variable) == (1, "None"), r.stdout


@pytest.mark.parametrize("argv, code, says", [
    (["render", "--help"], 0, "usage: pathtrace render"),
    (["render", "cornell-box", "-o", "x.png", "--bogus"], 2, "unrecognized arguments: --bogus"),
    (["render", "no-such-scene.xml", "-o", "x.png"], 1, "does not exist"),
    (["scenes"], 0, "cornell-box")])
def test_a_command_done_before_the_drivers_have_started_does_not_wait_for_them(tmp_path, argv, code, says):
    """`render` and `view` start the OpenCL drivers early in a thread (app/device/loader.py:
    start_drivers_early); a command that ends before it needs them (help, an option refused, a
    missing scene) leaves at once, with its status and its output, not after a slow driver's
    start (here one of 60 s); other commands start none."""
    child = f"""
import sys, time
import pathtrace.device.loader as loader
loader.start_drivers = lambda: (print("starting the drivers", file=sys.stderr, flush=True), time.sleep(60))
sys.argv = ["pathtrace", *{argv!r}]
from pathtrace.cli.console import run
run()
"""
    start = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", child], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert time.perf_counter() - start < 30 and r.returncode == code, (r.returncode, r.stderr[-2000:])
    assert says in r.stdout + r.stderr and "Traceback" not in r.stderr
    if argv[0] not in ("render", "view"):
        assert "starting the drivers" not in r.stderr


@pytest.mark.specialised     # the scene's own program, which is cached where the generic one is not
def test_a_damaged_kernel_cache_is_rebuilt(tmp_path):
    """A truncated cache file (the first half of a valid one) crashed PoCL at every start. (PoCL
    keeps its kernels in its own cache, app/device/opencl.py keeps_own_cache: here it uses ours, as the
    drivers that keep none do.) Truncated, garbage or empty, each is rebuilt."""
    env_cache = tmp_path / "cache"
    ours = ("import sys, pathtrace.device.opencl as d; d.keeps_own_cache = lambda device: False; "
            "sys.argv[0] = 'pathtrace'; from pathtrace.cli.console import run; run()")
    # simple's own program, whose binary PoCL makes in a second, where the generic program's takes ten
    run = lambda: subprocess.run([sys.executable, "-c", ours, "render", "simple", "-o", str(tmp_path / "o.png"),
                                  "--size", "8x8", "--spp", "1", "-q", "--program", "specialised"], cwd=ROOT,
                                 capture_output=True, text=True,
                                 env={**os.environ, "PATHTRACE_CACHE": str(env_cache)}, timeout=300)
    assert run().returncode == 0
    whole = {f: f.read_bytes() for f in sorted(env_cache.glob("*.bin"))}
    assert whole
    for damage in ("truncated", "garbage", "empty"):
        damaged = {f: {"truncated": data[: len(data) // 2], "garbage": os.urandom(len(data)), "empty": b""}[damage]
                   for f, data in whole.items()}
        for f, data in damaged.items():
            f.write_bytes(data)
        r = run()
        assert r.returncode == 0, (damage, r.stderr)
        # the scene's program rebuilt and cached again; the BVH builder's, where this run made none
        # (its opening ended after the host built the tree: pathtrace.compiler.builder), unread
        rebuilt = {f for f in whole if f.read_bytes() != damaged[f] and len(f.read_bytes()) > 32}
        assert rebuilt and all(f in rebuilt or f.read_bytes() == damaged[f] for f in whole), damage


def test_a_full_standard_output_gets_one_line():
    with open("/dev/full", "w") as full:
        r = subprocess.run([sys.executable, "-m", "pathtrace", "scenes"], cwd=ROOT, stdout=full, stderr=subprocess.PIPE,
                           text=True, timeout=60)
    assert r.returncode == 1 and r.stderr == "pathtrace: error: cannot write the standard output (No space left on device)\n"


def test_an_incomplete_install_says_what_is_missing(tmp_path):
    """A copy of the package without its assets folder (an install that lost it) says so in
    one line, not as a failure to write the standard output: only an OSError of the standard
    output itself is reported as one."""
    import shutil
    shutil.copytree(ROOT / "app", tmp_path / "pathtrace", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(ROOT / "kernels", tmp_path / "kernels")
    r = subprocess.run([sys.executable, "-m", "pathtrace", "bench", "--device", "cpu", "--no-cold", "--scenes",
                        "simple", "--spp", "1", "--size", "8x8"], cwd=tmp_path, capture_output=True, text=True,
                       timeout=120, env={**os.environ, "PYTHONPATH": str(tmp_path)})
    assert r.returncode == 1, r.stderr
    assert r.stderr.strip().splitlines() == ["pathtrace: error: pathtrace is incomplete: its 'assets' folder is missing; "
                                             "install it again (./install.sh in a checkout)"], r.stderr


def test_sigterm_stops_a_render_and_leaves_no_file(tmp_path):
    import signal
    import time
    p = subprocess.Popen([sys.executable, "-m", "pathtrace", "render", "spheres8k", "-o", str(tmp_path / "a.exr"),
                          "--size", "640x360", "--spp", "100000"], cwd=ROOT, stderr=subprocess.PIPE, text=True,
                         env=dict(os.environ))
    deadline = time.time() + 60
    line = ""
    while "spp" not in line and time.time() < deadline:   # wait until rendering has begun
        line = p.stderr.readline()
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 143 and "nothing written" in err and "Traceback" not in err     # 128 + SIGTERM
    assert not list(tmp_path.iterdir())


def test_a_bad_option_is_one_line_pointing_at_its_subcommands_help():
    r = in_process("render", "simple", "-o", "x.png", "--bogus")
    assert r.returncode == 2 and r.stderr == ("pathtrace render: error: unrecognized arguments: --bogus "
                                              "(see 'pathtrace render -h')\n"), r.stderr


def test_no_command_names_the_commands():
    r = in_process()
    assert r.returncode == 2 and r.stderr == ("pathtrace: error: give a command: render, view, bench, farm, convert, "
                                              "devices, scenes (see 'pathtrace -h')\n"), r.stderr
    r = in_process("farm")
    assert r.returncode == 2 and r.stderr == "pathtrace farm: error: give a command: render (see 'pathtrace farm -h')\n"



ENDINGS = {    # a command line of each kind of ending, and its exit status
    "unknown option": (["render", "simple", "-o", "o.png", "--sppp", "4"], 2),
    "invalid choice": (["render", "simple", "-o", "o.png", "--tonemap", "acse"], 2),
    "bad value": (["render", "simple", "-o", "o.png", "--size", "0x10"], 2),
    "bad scene file": (["render", "scene.toml", "-o", "o.png"], 1),
    "no such scene": (["render", "cornel-box", "-o", "o.png"], 1),
    "listing": (["scenes"], 0),
}


@pytest.mark.parametrize("case", ENDINGS)
def test_in_process_runs_are_what_the_entry_point_prints(tmp_path, case):
    """in_process (tests/commands.py), which the tests of messages use, against `python -m
    pathtrace`: the same exit status as the shell sees it, the same standard output and the same
    standard error, byte for byte, for each kind of ending (argparse's exit 2, a UserError's 1, a
    listing's 0)."""
    scene = write(tmp_path, GOOD.replace("radius = 1", "radius = -1"))
    args, status = ENDINGS[case]
    here, there = in_process(*args, cwd=tmp_path), pathtrace(*args, cwd=tmp_path)
    assert (here.returncode, here.stdout, here.stderr) == (there.returncode, there.stdout, there.stderr)
    assert there.returncode == status and (there.stderr if status else there.stdout).strip()
    assert list(tmp_path.iterdir()) == [scene]



def test_a_command_in_process_leaves_the_process_as_it_found_it(tmp_path):
    """What a command changes of its process, in_process puts back for the tests after it: a render
    with --program specialised sets PATHTRACE_PROGRAM and opens a device in that mode, and its
    finished write leaves SIGINT and SIGTERM ignored (pathtrace.cli.interrupts.FinalWrite)."""
    import signal

    from pathtrace import api

    def state():
        return (os.getcwd(), dict(os.environ), dict(api._backends),
                signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))
    before = state()
    r = in_process("render", "simple", "-o", "o.png", "--size", "8x6", "--spp", "1", "-q", "--program", "specialised",
                   cwd=tmp_path)
    assert r.returncode == 0 and (tmp_path / "o.png").read_bytes()[:4] == b"\x89PNG", r.stderr
    assert state() == before

def test_the_parser_loads_no_numpy_pyopencl_or_scene_module():
    """Building the command line's parser and refusing a bad option (each command's parser, and
    each kind of refusal) imports neither NumPy nor PyOpenCL nor the scene, light or material
    modules: the constants the options offer live in modules that import nothing
    (pathtrace.rendering.choices, pathtrace.device.programs, pathtrace.bench.default_scenes), so that
    a mistyped command ends in a fifth of a second, not one (issue #60)."""
    heavy = ("numpy", "pyopencl", "cv2", "pathtrace.scene", "pathtrace.lights", "pathtrace.materials")
    render = ["render", "simple", "-o", "o.png"]
    refused = [render + ["--tonemap", "acse"], render + ["--bogus"], render + ["--filter", "gauss"], render + ["--aov", "x"],
               ["view", "simple", "--light-sampler", "x"], ["bench", "--program", "x"], ["convert", "simple"],
               ["farm", "render", "simple", "--rr", "x"], ["devices", "--bogus"], ["nosuchcommand"]]
    code = f"""
import sys
from pathtrace.cli.main import main
for argv in {refused!r}:
    try:
        main(argv)
    except SystemExit as e:
        assert e.code == 2, (argv, e.code)
    else:
        raise AssertionError(argv)
print(sorted(m for m in {heavy!r} if m in sys.modules))
"""
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout == "[]\n", (r.stdout, r.stderr[-2000:])


def test_the_progress_bar_ends_with_the_real_rate(tmp_path):
    r = in_process("render", "simple", "-o", tmp_path / "a.png", "--size", "64x36", "--spp", "16")
    assert r.returncode == 0
    last = [line for line in r.stderr.replace("\r", "\n").splitlines() if line.startswith("simple 64x36: ")][-1]
    assert last.startswith("simple 64x36: 100%") and "16/16 spp" in last
    assert float(last.split("Msamples/s")[0].split()[-1]) > 0


def test_a_progress_bar_in_a_log_is_redrawn_seldom(tmp_path):
    """Standard error that is not a terminal (a log) gets a bar's first and last draws, and one
    every LOG_INTERVAL between, not ten a second: a render of a second or more drew its bar
    once or twice, where tqdm's own interval drew it at every few launches."""
    from pathtrace.cli.progress import LOG_INTERVAL
    r = in_process("render", "simple", "-o", tmp_path / "a.png", "--size", "160x90", "--spp", "1024")
    assert r.returncode == 0, r.stderr
    draws = [line for line in r.stderr.split("\r") if line.startswith("simple 160x90: ")]
    seconds = float(draws[-1].split("[")[1].split("<")[0].split(":")[-1])
    assert draws[-1].startswith("simple 160x90: 100%")
    assert len(draws) <= 2 + seconds / LOG_INTERVAL + 1, (len(draws), seconds)


def test_render_prints_each_phase_with_its_time_unless_quiet(tmp_path):
    """One line per phase, in order, around the progress bar; -q prints none of them (and still
    the device and what was written)."""
    import re
    out = tmp_path / "a.png"
    args = ("render", "simple", "-o", out, "--size", "16x9", "--spp", "2", "--denoise")
    r = pathtrace(*args)
    assert r.returncode == 0, r.stderr
    lines = r.stderr.replace("\r", "\n").splitlines()
    timed = [k for k, line in enumerate(lines) if re.search(r" in \d+\.\d\d s( \(.*\))?$", line)]
    phases = [lines[k].rsplit(" in ", 1)[0].split(" (")[0] for k in timed]
    assert phases == ["opened Open Image Denoise", "loaded simple", "opened the device and built the generic kernels",
                      "compiled the scene", "prepared the renderer", "denoised", f"wrote {out}"], lines
    assert lines[timed[3]].startswith("compiled the scene (5 spheres, BVH in ")
    bar = [k for k, line in enumerate(lines) if line.startswith("simple 16x9: 100%")]
    assert bar and timed[4] < bar[0] < timed[5]
    r = pathtrace(*args, "-q")
    assert r.returncode == 0 and r.stderr.splitlines()[1:] == [f"wrote {out}"], r.stderr
    assert r.stderr.startswith("device: ")


def test_running_out_of_memory_gets_one_line(monkeypatch, capsys):
    import pathtrace.cli.main as cli
    import pathtrace.scene

    def huge(name):
        raise MemoryError
    monkeypatch.setattr(pathtrace.scene, "load_scene", huge)
    assert cli.main(["render", "simple", "-o", "/tmp/never.png"]) == 1
    assert capsys.readouterr().err.startswith("pathtrace: error: out of memory")


def test_a_huge_or_binary_value_is_not_echoed_whole(tmp_path):
    scene = write(tmp_path, GOOD.replace('type = "diffuse"', 'type = "' + "x" * 1_000_000 + '\\u0000"'))
    r = in_process("render", scene, "-o", tmp_path / "o.png", "--spp", "1")
    assert r.returncode == 1 and "material.type: must be one of" in r.stderr
    assert len(r.stderr) < 600 and "\0" not in r.stderr


@pytest.mark.parametrize("where", ["scene", "map"])
def test_a_name_too_long_for_the_file_system_gets_one_line(tmp_path, where):
    long = "b" * 300
    scene = tmp_path / f"{long}.toml" if where == "scene" else \
        write(tmp_path, GOOD.replace("color = 0.5", f'map = "{long}.hdr"'))
    r = in_process("render", scene, "-o", tmp_path / "o.png", "--spp", "1")
    assert r.returncode == 1 and r.stderr.strip().endswith("File name too long") and "Traceback" not in r.stderr


@pytest.mark.parametrize("outputs", [["x.png", "x.png"], ["x.png", "./x.png"], ["x.exr", "x.albedo.exr"]],
                         ids=["same", "same-file", "aov-clash"])
def test_an_output_named_twice_is_refused(tmp_path, outputs):
    """Two outputs (or an output and another's --aov image) that are one file: one line, nothing
    written, where it used to write the file twice without a word."""
    args = [a for o in outputs for a in ("-o", o)]
    r = in_process("render", "simple", *args, "--aov", "albedo", "--size", "8x8", "--spp", "1", "-q", cwd=tmp_path)
    assert r.returncode == 1 and "would be written twice" in r.stderr and len(r.stderr.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


# --- round 3 of the fuzzer (#28): each class of traceback it found is one line now -----------

@pytest.mark.parametrize("spec", ["²", "cpu:²", "9" * 5000, "gpu:0\nx"])
def test_a_device_spec_of_odd_digits_is_one_line(spec):
    r = in_process("render", "simple", "-o", "o.png", "--spp", "1", "--device", spec, "-q")   # no "loaded" line
    assert r.returncode == 1 and len(r.stderr.splitlines()) == 1, r.stderr
    assert "no OpenCL device matches" in r.stderr and len(r.stderr) < 300


@pytest.mark.parametrize("command", [["render", "simple", "--spp", "1", "-o"], ["convert", "simple", "-o"],
                                     ["bench", "--quick", "--json"]], ids=["render", "convert", "bench"])
def test_an_output_name_too_long_for_the_file_system_is_one_line(tmp_path, command):
    suffix = {"render": ".png", "convert": ".toml", "bench": ".json"}[command[0]]
    r = in_process(*command, tmp_path / ("a" * 300 + suffix))
    assert r.returncode == 1 and "File name too long" in r.stderr and len(r.stderr.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_convert_refuses_to_write_over_the_scene_it_converts(tmp_path):
    """A hand-written TOML file, comments and all, was replaced by its own conversion."""
    scene = tmp_path / "s.toml"
    scene.write_text("# mine\n[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = { type = \"diffuse\", rho_d = 0.5 }\n")
    text = scene.read_text()
    r = in_process("convert", scene, "-o", tmp_path / "." / "s.toml")
    assert r.returncode == 1 and "is the scene being converted" in r.stderr and len(r.stderr.splitlines()) == 1
    assert scene.read_text() == text and sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]
    assert in_process("convert", scene, "-o", tmp_path / "t.toml").returncode == 0


def test_convert_names_a_shipped_map_by_its_name_not_a_path_into_the_installation(tmp_path):
    """`convert demo` wrote a path into the environment's site-packages, which breaks when it is
    made again; the TOML reader finds a shipped map by its bare name. A file of that name beside
    the output would hide it: then the path is written."""
    from pathtrace.scene import load_scene
    assert in_process("convert", "demo", "-o", tmp_path / "d.toml").returncode == 0
    assert 'map = "venice_sunset_1k.hdr"' in (tmp_path / "d.toml").read_text()
    assert np.array_equal(load_scene(str(tmp_path / "d.toml")).environment.image, load_scene("demo").environment.image)
    (tmp_path / "venice_sunset_1k.hdr").write_bytes(b"")
    assert in_process("convert", "demo", "-o", tmp_path / "e.toml").returncode == 0
    assert 'map = "venice_sunset_1k.hdr"' not in (tmp_path / "e.toml").read_text()
    # a Mitsuba scene's shipped map keeps its rows at the poles (a review found them dropped)
    xml = ROOT / "tests" / "scenes" / "envmap-spheres.xml"
    assert in_process("convert", xml, "-o", tmp_path / "m.toml").returncode == 0
    assert load_scene(str(tmp_path / "m.toml")).environment.rows == load_scene(str(xml)).environment.rows == "poles"


def test_outputs_that_are_not_regular_files_are_refused_and_kept(tmp_path):
    """A link to a device (as root, rename() replaced /dev/full itself), a FIFO, a folder."""
    (tmp_path / "full.png").symlink_to("/dev/full")
    os.mkfifo(tmp_path / "fifo.png")
    (tmp_path / "dir.png").mkdir()
    for name in ("full.png", "fifo.png", "dir.png"):
        r = in_process("render", "simple", "-o", tmp_path / name, "--size", "8x6", "--spp", "1", "-q")
        assert r.returncode == 1 and len(r.stderr.splitlines()) == 1, r.stderr
    assert os.readlink(tmp_path / "full.png") == "/dev/full" and stat.S_ISFIFO(os.lstat(tmp_path / "fifo.png").st_mode)


def test_listing_to_a_closed_standard_output_is_one_line():
    r = subprocess.run(f"{shlex.quote(sys.executable)} -m pathtrace scenes >&-", shell=True, cwd=ROOT,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1 and r.stderr == "pathtrace: error: cannot write the standard output: it is closed\n"


@pytest.mark.parametrize("field", ['[environment]\nmap = "a\\u0000b.hdr"\n',
                                   '[[meshes]]\nfile = "a\\u0000b.ply"\nmaterial = { type = "diffuse", rho_d = 0.5 }\n'],
                         ids=["map", "mesh"])
def test_a_nul_byte_in_a_file_name_is_one_line(tmp_path, field):
    scene = tmp_path / "s.toml"
    scene.write_text(field + '[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = { type = "diffuse", rho_d = 0.5 }\n')
    r = in_process("render", scene, "-o", tmp_path / "o.png", "--spp", "1")
    assert r.returncode == 1 and "a file name cannot hold a NUL byte" in r.stderr and "\\x00" in r.stderr
    assert len(r.stderr.splitlines()) == 1


def test_farm_patterns_and_addresses_of_odd_text_are_one_line():
    from pathtrace.cli.farm import farm_output
    from pathtrace.rendering.farm import _check_reachable
    for pattern in ("{name.x}.png", "{frame[0]}.png", "{0}.png", "{name!z}.png"):
        with pytest.raises(UserError, match="only {name} and {frame} may stand in braces"):
            farm_output(pattern, "simple", 0, 1)
    for address in ("127.0.0.1:²", "127.0.0.1:" + "9" * 5000, "host:99999"):
        with pytest.raises(UserError, match="give host:port") as e:
            _check_reachable(address)
        assert len(str(e.value)) < 300


@pytest.mark.parametrize("signum", ["SIGINT", "SIGTERM"])
def test_a_signal_after_the_outputs_are_written_does_not_fail_the_command(tmp_path, signum):
    """The signal arrives just as the last output is complete (sent from inside the commit of
    the writes): the render is whole, so the exit is 0, not 'interrupted' (130)."""
    code = f"""
import os, signal, sys
import pathtrace.io.images as io
from pathtrace.cli.console import run
commit = io.Staged.commit
def commit_then_signal(self):
    commit(self)
    os.kill(os.getpid(), signal.{signum})
io.Staged.commit = commit_then_signal
sys.argv = ["pathtrace", "render", "simple", "-o", {str(tmp_path / "o.png")!r}, "--size", "8x6", "--spp", "1", "-q"]
run()
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, (r.returncode, r.stderr)
    assert (tmp_path / "o.png").read_bytes()[:4] == b"\x89PNG"


def test_a_name_with_a_newline_is_shown_on_one_line(tmp_path):
    r = in_process("render", "simple", "-o", tmp_path / "a\nb.png", "--size", "8x6", "--spp", "1", "-q")
    assert r.returncode == 0 and r.stderr.splitlines()[-1] == f"wrote {tmp_path}/a\\nb.png"


def test_an_interrupt_dropped_by_python_still_ends_the_render(tmp_path):
    """A signal whose KeyboardInterrupt is raised inside a weak reference's callback (a garbage
    collection between launches: Python prints and drops such exceptions) used to leave the render
    running to its end; now the next launch's progress ends it, with the one line and no
    traceback. The child sends itself SIGTERM from such a callback once samples are in (without
    the fix it renders all 3000 samples and writes the image)."""
    out = tmp_path / "o.png"
    child = f"""
import os, signal, sys, weakref
import tqdm
original = tqdm.tqdm.update
fired = []
class Token:
    pass
def callback(ref):
    os.kill(os.getpid(), signal.SIGTERM)
    for _ in range(100000):     # a loop: Python runs the signal's handler here, in the callback
        pass
def update(self, n=1):          # the progress bar's update, in the main thread
    if not fired and self.n > 0:
        token = Token()
        fired.append(weakref.ref(token, callback))
        del token               # the callback runs here, and the signal's exception is dropped in it
    return original(self, n)
tqdm.tqdm.update = update
sys.argv = ["pathtrace", "render", "simple", "-o", {str(out)!r}, "--spp", "3000", "--size", "32x18"]
from pathtrace.cli.console import run
run()
"""
    r = subprocess.run([sys.executable, "-c", child], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 143 and "nothing written" in r.stderr, r.stderr      # 128 + SIGTERM
    assert "Traceback" not in r.stderr and "Exception ignored" not in r.stderr, r.stderr
    assert not out.exists()


@pytest.mark.parametrize("fails", ["the devices", "the scene"])
def test_an_error_after_an_interrupt_ends_as_the_interrupt(tmp_path, monkeypatch, fails):
    """A kernel build under way when SIGINT or SIGTERM arrives fails (PoCL's compiler, LLVM, removes
    its temporary files on the signal), which is the interrupt's doing: the command ends as
    interrupted (130), not with an error about the device. Here a device that cannot be opened,
    inside the render, and a scene file that cannot be read, before it, stand for the failure."""
    from pathtrace.cli import interrupts
    monkeypatch.setattr(interrupts, "_interrupted", True)
    out = tmp_path / "o.png"
    scene, device = ("simple", "no-such-device") if fails == "the devices" else (tmp_path / "none.toml", "cpu")
    r = in_process("render", scene, "--device", device, "-o", out, "--size", "8x6", "--spp", "1")
    assert r.returncode == 130 and "interrupted" in r.stderr and "error" not in r.stderr, r.stderr
    assert not out.exists()


def test_a_pbrt_render_to_exr_imports_no_other_scene_reader_and_no_opencv(tmp_path):
    """What a command imports is part of the wait for its first image (docs/notes/performance-2026-11.md,
    2026-11-26): a pbrt-v4 scene rendered to EXR loads neither the other scene readers nor
    OpenCV, and a PNG then does load OpenCV, which encodes it."""
    readers = ("pathtrace.scene.mitsuba", "pathtrace.scene.toml_reader", "pathtrace.scene.builtin")
    for out, expected in (("x.exr", []), ("x.png", ["cv2"])):
        code = ("import sys\nfrom pathtrace.cli.main import main\n"
                f"code = main(['render', {str(ROOT / 'tests' / 'scenes' / 'cbox.pbrt')!r}, '--size', '8x8', "
                f"'--spp', '1', '--device', 'cpu', '-q', '-o', {str(tmp_path / out)!r}])\n"
                f"print(code, sorted(m for m in {('cv2',) + readers!r} if m in sys.modules))\n")
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
        assert r.returncode == 0 and r.stdout.strip().splitlines()[-1] == f"0 {expected}", (r.stdout, r.stderr)


def test_kernels_that_count_more_samples_than_they_drew_write_no_image(tmp_path, monkeypatch):
    """A pixel keeps at most the samples drawn; more is a program built wrongly for its device
    (NVIDIA's driver 580 and the generic program: docs/notes/performance-2026-11.md, 2026-11-30),
    whose image is wrong too: one line, a non-zero exit and no file (one pixel's count one over
    here, found as the render ends)."""
    from pathtrace.rendering.renderer import Renderer
    read_sum = Renderer.read_sum

    def overcounted(self):
        sums = read_sum(self).copy()
        sums[2, 3, 3] += 1.0
        return sums
    monkeypatch.setattr(Renderer, "read_sum", overcounted)
    out = tmp_path / "o.png"
    r = in_process("render", "simple", "-q", "--spp", "2", "--size", "8x8", "-o", out)
    errors = [line for line in r.stderr.splitlines() if "error" in line]
    assert r.returncode == 1 and not out.exists(), r.stderr
    assert errors == ["pathtrace: error: simple: 1 pixels kept more samples than were drawn (up to 3 of 2): the "
                      "kernels were built wrongly for this device; no image is given (pathtrace devices --check "
                      "tests the generic kernels; --program specialised avoids them)"], r.stderr
