"""A fuzzer of pbrt-v4 files, the Python API and the outputs (#61), with the bar of the others
(tests/test_fuzz_scenes.py): bad input exits 1 with one error line naming the file (or raises
pathtrace.UserError), never a traceback, a hang, a line from below (NumPy's RuntimeWarning), a
non-finite pixel in a render that succeeded, or a file left behind or half-written.

- pbrt-v4 files: a valid scene with pieces drawn in: singular and tiny transforms before the
  camera, a mesh with normals, an infinite light or an instance; materials (mix without its
  materials, reflectances out of [0, 1], an imagemap of 3e38 texels), textures, area lights
  (negative scale, power over a tiny triangle, a blackbody of no visible light, a zero
  spectrum), lights, vertex indices beyond 32 bits, unknown parameters by the thousand;
- the API: a loaded scene's settings, camera, spheres, meshes, materials and environment set
  to odd values before a render, odd arguments to render, progressive, write and tonemap, and
  dicts that hold themselves, nest deep or have keys that are not strings;
- outputs: render, convert and write onto a FIFO, a folder, a missing folder, with a second
  output that fails (none is written), a full set of convert's side files; and a temporary file
  a killed run left (.pathtrace-<pid>-...) swept by the next write.

The cases of each class run in one process of their own (tests/fuzz_batch.py) with a time limit,
so that the device is opened and the kernels built once; the generic program renders them all."""

import json
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest

from pathtrace.io.images import read_hdr, write_image
from tests.fuzz_batch import run_batch

DEVICE = os.environ.get("PATHTRACE_TEST_DEVICE", "cpu")
ALLOWED = ("device: ", "wrote ", "pathtrace: warning: ", "pathtrace: error: ")


def check_result(case: dict, result: dict, names: tuple, before: set, outputs: list):
    """A command's or a code case's outcome: exit 0 with every output written and finite, or 1
    with one error line naming one of `names` (a file of the case) and no output; only
    pathtrace's lines on standard error; no file left beside those that were there (`before`)."""
    shown = json.dumps(case)[:3000] + "\n" + json.dumps(result)[:3000]
    assert not result["traceback"], shown
    assert result["status"] in (0, 1), shown
    lines = result["stderr"].splitlines()
    assert all(line.startswith(ALLOWED) for line in lines), shown
    errors = [line for line in lines if line.startswith("pathtrace: error: ")]
    if "argv" in case:
        message = errors[0] if errors else ""
        assert (len(errors) == 1) == (result["status"] == 1), shown
    else:
        message = result["error"]
        assert not errors, shown
    folder = Path(case["cwd"])
    now = {p.name for p in folder.iterdir()}
    if result["status"] == 1:
        assert any(name in message for name in names), shown
        assert now == before, shown + f"\nleft: {sorted(now - before)}, gone: {sorted(before - now)}"
    else:
        assert now == before | set(outputs), shown + f"\nnow: {sorted(now)}"
        for name in outputs:
            if name.endswith(".exr"):
                assert np.all(np.isfinite(read_hdr(folder / name, "test"))), shown


# -- pbrt-v4 files --

ODD = ["0", "-1", "1e-30", "3e38", "1e20", "nan", "2", "0.5", "9223372036854775808", "1e-200"]
HEAD = """Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 6 ]
Sampler "independent" "integer pixelsamples" 1
{camera}
LookAt {look}
Camera "perspective" "float fov" 45
WorldBegin
LightSource "point" "rgb I" [ 4 4 4 ] "point3 from" [ 0 2 2 ]
"""
TRIANGLE = 'Shape "trianglemesh" "point3 P" [ -1 -1 0  1 -1 0  0 1 0 ] "integer indices" [ 0 1 2 ]'
SINGULAR = ["Scale 0 0 0", "Scale 1e-200 1e-200 1e-200\nScale 1e-200 1e-200 1e-200", "Scale 1e-30 1e-30 1e-30"]


TINY = 'Shape "trianglemesh" "point3 P" [ 0 0 0  1e-30 0 0  0 1e-30 0 ] "integer indices" [ 0 1 2 ]'
# the pieces of a world, {x} an odd number, {image} a texture or map file, {before} a transform
PIECES = [
    'Material "diffuse" "rgb reflectance" [ {x} 0.5 0.5 ]\n' + TRIANGLE,
    'Material "diffuse" "float reflectance" {x}\n' + TRIANGLE,
    'Material "mix" "float amount" 0.5\n' + TRIANGLE,
    'MakeNamedMaterial "a" "string type" "diffuse"\nMaterial "mix" "string materials" [ "a" "a" ] "float amount" {x}\n'
    + TRIANGLE,
    'Material "coateddiffuse" "rgb reflectance" [ 0.5 0.5 0.5 ] "float roughness" {x}\n' + TRIANGLE,
    'Material "conductor" "rgb reflectance" [ {x} {x} {x} ]\n' + TRIANGLE,
    'Material "dielectric" "float eta" {x}\n' + TRIANGLE,
    'Texture "t" "spectrum" "imagemap" "string filename" "{image}"\nMaterial "diffuse" "texture reflectance" "t"\n'
    + TRIANGLE,
    'Texture "t" "spectrum" "imagemap" "string filename" "{image}" "float scale" {x}\n'
    'Material "diffuse" "texture reflectance" "t"\n' + TRIANGLE,
    'Texture "t" "spectrum" "checkerboard" "float tex1" {x} "float tex2" 0.5\n'
    'Material "diffuse" "texture reflectance" "t"\n' + TRIANGLE,
    'Texture "t" "spectrum" "scale" "float scale" {x}\nMaterial "diffuse" "texture reflectance" "t"\n' + TRIANGLE,
    'Texture "t" "spectrum" "mix" "float amount" {x}\nMaterial "diffuse" "texture reflectance" "t"\n' + TRIANGLE,
    'Texture "t" "float" "constant" "float value" {x}\nMaterial "coateddiffuse" "texture roughness" "t"\n' + TRIANGLE,
    'AttributeBegin\nAreaLightSource "diffuse" "float scale" {x}\n' + TRIANGLE + '\nAttributeEnd',
    'AttributeBegin\nAreaLightSource "diffuse" "float power" {x}\n' + TINY + '\nAttributeEnd',
    'AttributeBegin\nAreaLightSource "diffuse" "float power" {x}\nShape "sphere" "float radius" 0.2\nAttributeEnd',
    'AttributeBegin\nAreaLightSource "diffuse" "blackbody L" [ {x} ]\n' + TRIANGLE + '\nAttributeEnd',
    'AttributeBegin\nAreaLightSource "diffuse" "spectrum L" [ 400 0 700 0 ] "float power" 10\n' + TRIANGLE
    + '\nAttributeEnd',
    'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [ {x} 1 1 ]\n' + TRIANGLE + '\nAttributeEnd',
    'AttributeBegin\n{before}\nLightSource "point" "rgb I" [ {x} 1 1 ]\nAttributeEnd',
    'AttributeBegin\n{before}\nLightSource "point" "float power" {x}\nAttributeEnd',
    'AttributeBegin\n{before}\nLightSource "spot" "float coneangle" {x}\nAttributeEnd',
    'AttributeBegin\n{before}\nLightSource "distant" "point3 to" [ 0 {x} 0 ]\nAttributeEnd',
    'AttributeBegin\n{before}\nLightSource "infinite" "rgb L" [ {x} 1 1 ]\nAttributeEnd',
    'AttributeBegin\n{before}\nLightSource "infinite" "string filename" "{image}" "float scale" {x}\nAttributeEnd',
    'AttributeBegin\n{before}\nShape "trianglemesh" "point3 P" [ -1 -1 0  1 -1 0  0 {x} 0 ] '
    '"integer indices" [ 0 1 2 ] "normal N" [ 0 0 1  0 0 1  0 0 1 ]\nAttributeEnd',
    'Shape "trianglemesh" "point3 P" [ -1 -1 0  1 -1 0  0 1 0 ] "integer indices" [ 0 1 {x} ]',
    'AttributeBegin\n{before}\nShape "sphere" "float radius" {x}\nAttributeEnd',
    'ObjectBegin "o"\n' + TRIANGLE + '\nObjectEnd\nAttributeBegin\n{before}\nObjectInstance "o"\nAttributeEnd',
    'ObjectBegin "o"\n' + TRIANGLE + '\nObjectEnd\nAttributeBegin\nScale {x} {x} {x}\nObjectInstance "o"\nAttributeEnd',
    TRIANGLE + "".join(f' "float bogus{i}" {{x}}' for i in range(3000)),
]
CAMERAS = ["", "Scale -1 1 1", *SINGULAR]
LOOKS = ["0 0 5  0 0 0  0 1 0", "0 0 5  0 0 0  0 1 0", "0 0 5  0 0 5  0 1 0", "0 0 5  0 0 0  0 0 0"]
BEFORE = ["", *SINGULAR, "Scale 1e30 1e30 1e30"]


def pbrt_files() -> list:
    """Each piece with two odd numbers in turn, under cameras and transforms in turn: a fixed
    list, so that every run covers each; then a few worlds of several pieces."""
    files, k = [], 0

    def fill(piece):
        nonlocal k
        k += 1
        return piece.format(x=ODD[k % len(ODD)], image=IMAGES[k % len(IMAGES)], before=BEFORE[k % len(BEFORE)])
    for piece in PIECES:
        for _ in range(2):
            head = HEAD.format(camera=CAMERAS[k % len(CAMERAS)] if k % 3 == 0 else "", look=LOOKS[k % len(LOOKS)]
                               if k % 5 == 0 else LOOKS[0])
            files.append(head + TRIANGLE + "\n" + fill(piece) + "\n")
    for j in range(4):
        head = HEAD.format(camera="", look=LOOKS[0])
        files.append(head + "\n".join(fill(PIECES[(j * 7 + i * 5) % len(PIECES)]) for i in range(3)) + "\n")
    return files


def _image_files(folder: Path):
    """The texture and map files the pbrt cases name: a good one, one of 3e38 texels and one of
    negative texels (PFM: any float goes), square (pbrt-v4's equal-area maps are)."""
    rng = np.random.default_rng(7)
    good = rng.uniform(0, 1, (4, 4, 3)).astype(np.float32)
    for name, image in (("good.pfm", good), ("huge.pfm", np.full((4, 4, 3), 3e38, np.float32)),
                        ("negative.pfm", -good)):
        header = b"PF\n4 4\n-1.0\n"
        (folder / name).write_bytes(header + np.ascontiguousarray(image[::-1]).tobytes())


IMAGES = ["good.pfm", "huge.pfm", "negative.pfm"]


def test_pbrt_files_render_finite_pixels_or_are_refused_in_one_line(tmp_path):
    files = pbrt_files()
    with tempfile.TemporaryDirectory(dir=tmp_path) as top:
        top = Path(top)
        cases, befores = [], []
        for k, text in enumerate(files):
            folder = top / f"case{k}"
            folder.mkdir()
            _image_files(folder)
            (folder / "scene.pbrt").write_text(text)
            befores.append({p.name for p in folder.iterdir()})
            cases.append({"cwd": str(folder), "argv": ["render", "scene.pbrt", "-o", "out.exr", "--size", "8x6",
                                                       "--spp", "1", "-q", "--device", DEVICE]})
        for case, result, before in zip(cases, run_batch(cases, top), befores):
            check_result(case, result, ("scene.pbrt", *IMAGES), before, ["out.exr"])


# -- the Python API --

BASE = {"camera": {"eye": [0, 1, 5], "look_at": [0, 0, 0]},
        "render": {"spp": 1, "width": 8, "height": 6},
        "spheres": [{"center": [0, 0, 0], "radius": 1, "material": {"type": "diffuse", "rho_d": 0.5}}],
        "meshes": [{"vertices": [[-2, -1, -2], [2, -1, -2], [0, -1, 2]], "faces": [[0, 1, 2]],
                    "material": {"type": "diffuse", "rho_d": 0.5}}]}
ODD_VALUES = ["0", "-1", "2**64", "1.5", "float('nan')", "float('inf')", "None", "'x'", "[]", "True", "(1, 2, 3)",
              "object()", "np.zeros(3)", "np.array([0, 0, 0])", "10**400 if False else 1e308"]
FIELDS = ["s.settings.width", "s.settings.height", "s.settings.spp", "s.settings.seed", "s.settings.max_depth",
          "s.settings.russian_roulette", "s.settings.nee", "s.settings.light_sampler", "s.settings.path_queue",
          "s.settings.path_sort",
          "s.camera.eye", "s.camera.look_at", "s.camera.up", "s.camera.vfov", "s.camera",
          "s.spheres[0, 0]", "s.spheres[0, 3]", "s.meshes[0].faces[0, 1]", "s.meshes[0].vertices[1, 2]",
          "s.meshes[0].normals", "s.meshes[0].material", "s.sphere_material[0]", "s.materials[0]",
          "s.environment.intensity", "s.environment.rotation", "s.environment.up"]
ARGUMENTS = ["device", "aovs", "steps", "size", "spp", "seed", "max_depth", "rr", "nee"]
CALLS = ["pathtrace.write({v}, np.zeros((2, 2, 3)))", "pathtrace.write('out.png', {v})",
         "pathtrace.write('out.exr', np.zeros((2, 2, 3)), exposure={v})", "pathtrace.tonemap({v})",
         "pathtrace.tonemap(np.zeros((2, 2, 3)), curve={v})", "pathtrace.load({v})", "pathtrace.material({v})"]
DICTS = ["d = {'camera': {}}; d['camera']['self'] = d; pathtrace.load_dict(d)",
         "d = x = {}\nfor _ in range(5000): x['a'] = {}; x = x['a']\n"
         "pathtrace.load_dict({'spheres': [{'center': [0, 0, 0], 'radius': 1, 'material': d}]})",
         "d = x = []\nfor _ in range(5000): x.append([]); x = x[0]\npathtrace.load_dict({'spheres': d})",
         "pathtrace.load_dict({**BASE, 'camera': {1: 2, 'eye': [0, 0, 1]}})",
         "pathtrace.load_dict({**BASE, 3.5: 1})"]
RENDER = ("img = pathtrace.render(s{args})\n"
          "img = img['image'] if isinstance(img, dict) else img\n"
          "assert np.all(np.isfinite(img)), 'a non-finite pixel'\n")
ARRAY_ELEMENTS = ("s.spheres[", "s.meshes[0].faces[", "s.meshes[0].vertices[", "s.sphere_material[")


def api_cases() -> list:
    """Every field, argument and call with odd values in turn (each field 3 of them, each
    argument and call 4), and the odd dicts: a fixed list, so that every run covers each."""
    start = f"BASE = {BASE!r}\ns = pathtrace.load_dict(BASE)\n"
    render = RENDER.format(args=f", device={DEVICE!r}")
    cases, k = [], 0
    for field in FIELDS:
        for _ in range(3):
            value, k = ODD_VALUES[k % len(ODD_VALUES)], k + 1
            change = f"{field} = {value}\n"
            if field.startswith(ARRAY_ELEMENTS):     # NumPy's own refusal of the value is not ours
                change = (f"try:\n    with np.errstate(all='ignore'):\n        {field} = {value}\n"
                          "except (TypeError, ValueError, OverflowError):\n    pass\n")
            # every other case renders before the change too: what it uploaded is then updated
            cases.append(start + (render if k % 2 else "") + change + render)
    for argument in ARGUMENTS:
        for _ in range(4):
            value, k = ODD_VALUES[k % len(ODD_VALUES)], k + 1
            device = "" if argument == "device" else f", device={DEVICE!r}"
            render = RENDER.format(args=f"{device}, {argument}={value}")
            if argument == "steps":              # progressive()'s
                render = render.replace("img = pathtrace.render(s", "img = list(pathtrace.progressive(s") \
                    .replace(")\n", "))[-1].image\n", 1)
            cases.append(start + render)
    for call in CALLS:
        for _ in range(4):
            value, k = ODD_VALUES[k % len(ODD_VALUES)], k + 1
            cases.append(call.format(v=value))
    return cases + [f"BASE = {BASE!r}\n" + d for d in DICTS]


def test_the_api_given_odd_values_renders_finite_pixels_or_raises_a_user_error(tmp_path):
    cases = []
    for k, code in enumerate(api_cases()):
        folder = tmp_path / f"case{k}"
        folder.mkdir()
        cases.append({"cwd": str(folder), "code": code})
    for case, result in zip(cases, run_batch(cases, tmp_path)):
        folder = Path(case["cwd"])
        written = [p.name for p in folder.iterdir()]
        check_result(case, result, ("",), set() if result["status"] == 1 else set(written), written)


# -- outputs --

STALE = ".pathtrace-999999999-left.exr"     # left by a process that no longer runs (no pid is that large)


def test_outputs_are_all_or_nothing_and_a_killed_runs_temporaries_are_swept(tmp_path):
    scene = tmp_path / "scenes"
    scene.mkdir()
    (scene / "s.pbrt").write_text(
        HEAD.format(camera="", look="0 0 5  0 0 0  0 1 0") + TRIANGLE + ' "normal N" [ 0 0 1  0 0 1  0 0 1 ]\n'
        'LightSource "infinite" "string filename" "sky.pfm"\n')
    sky = np.random.default_rng(1).uniform(0, 1, (8, 8, 3)).astype(np.float32)
    write_image(scene / "sky.pfm", sky, what="test")
    render = ["render", str(scene / "s.pbrt"), "--size", "8x6", "--spp", "1", "-q", "--device", DEVICE]
    convert = ["convert", str(scene / "s.pbrt")]
    # (argv, how the folder is prepared, the outputs of a success: None where it must fail)
    plans = [
        (render + ["-o", "out.exr"], "stale", ["out.exr"]),
        (render + ["-o", "out.exr", "--aov", "albedo"], "aov folder", None),
        (render + ["-o", "fifo.exr"], "fifo", None),
        (render + ["-o", "folder.exr"], "folder", None),
        (render + ["-o", "missing/out.exr"], "", None),
        (render + ["-o", "out.exr", "-o", "out.png"], "", ["out.exr", "out.png"]),
        (convert + ["-o", "s.toml"], "stale", ["s.toml", "s.environment.exr", "s.meshes"]),
        (convert + ["-o", "s.toml"], "map fifo", None),
        (convert + ["-o", "s.toml"], "mesh folder", None),
        (convert + ["-o", "s.toml"], "meshes file", None),
        (convert + ["-o", "s.toml"], "toml folder", None),
    ]
    code = [("pathtrace.write('out.exr', np.ones((2, 2, 3)))", "stale", ["out.exr"]),
            ("pathtrace.write('folder.exr', np.ones((2, 2, 3)))", "folder", None),
            ("pathtrace.write('fifo.png', np.ones((2, 2, 3)))", "fifo", None),
            ("pathtrace.load('fifo.toml')", "fifo", None)]
    cases, expected = [], []
    for k, (what, prepare, outputs) in enumerate(plans + code):
        folder = tmp_path / f"case{k}"
        folder.mkdir()
        _prepare(folder, prepare)
        before = {p.name for p in folder.iterdir()} - {STALE}
        key = "argv" if isinstance(what, list) else "code"
        cases.append({"cwd": str(folder), key: what})
        expected.append((before, outputs))
    for case, result, (before, outputs) in zip(cases, run_batch(cases, tmp_path), expected):
        shown = json.dumps(case) + "\n" + json.dumps(result)
        assert result["status"] == (1 if outputs is None else 0), shown
        check_result(case, result, ("out", "fifo", "folder", "missing", "s.", "nan", "NaN", "albedo"),
                     before, outputs or [])


def _prepare(folder: Path, how: str):
    if how == "stale":
        (folder / STALE).write_bytes(b"half an image")
    elif how == "fifo":
        for name in ("fifo.exr", "fifo.png", "fifo.toml"):
            os.mkfifo(folder / name)
    elif how == "folder":
        (folder / "folder.exr").mkdir()
    elif how == "aov folder":
        (folder / "out.albedo.exr").mkdir()
    elif how == "map fifo":
        os.mkfifo(folder / "s.environment.exr")
    elif how == "mesh folder":
        for name in ("0000.ply", "0001.ply"):        # where the mesh's file goes
            (folder / "s.meshes" / name).mkdir(parents=True)
    elif how == "meshes file":
        (folder / "s.meshes").write_text("not a folder")
    elif how == "toml folder":
        (folder / "s.toml").mkdir()


def test_a_batch_fails_on_a_line_below_pythons_capture(tmp_path):
    """What a driver or OpenCV writes to the file descriptor itself, which no case's capture
    sees, fails the batch that printed it (tests/fuzz_batch.py: run_batch)."""
    import pytest
    case = {"cwd": str(tmp_path), "code": "import os; os.write(2, b'[ WARN:0] imread_: a line from below\\n')"}
    with pytest.raises(AssertionError, match="a line from below"):
        run_batch([case], tmp_path)
    assert run_batch([{"cwd": str(tmp_path), "code": "import sys; print('captured', file=sys.stderr)"}],
                     tmp_path)[0]["stderr"] == "captured\n"
