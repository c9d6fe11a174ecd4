"""A scene-file fuzzer (#12): TOML files generated around the valid shape of a scene (every field
sometimes replaced by a value of another type, a huge or tiny or non-finite number, an empty or
nested container, or left out; the environment map sometimes a good file, sometimes a damaged
one, a folder or none; material parameters, opacities and normal and bump maps sometimes
textures, whose images are good, damaged or missing files) are rendered by the command line, in batches of BATCH in a process
with a time limit (tests/fuzz_batch.py), on the tests' device. Each must either exit 0 having
written an image of finite pixels, or exit 1 with one error line that names the file; never a
traceback, a signal, a hang, a warning from below (NumPy's, OpenCV's) or a file left behind. A
bounded number of examples runs on every CI run."""

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from PIL import Image as PILImage
from hypothesis import strategies as st

from pathtrace.io.images import read_hdr
from pathtrace.scene.toml_reader import FILE_TYPES, MATERIAL_TYPES
from tests.fuzz_batch import run_batch

ROOT = Path(__file__).resolve().parent.parent
GOOD_MAP = ROOT / "assets" / "envmaps" / "studio_small_03_1k.hdr"
# environment maps beside each case's scene file, good and damaged: file name -> how it is made
MAPS = {
    "good.hdr": lambda path: path.write_bytes(GOOD_MAP.read_bytes()),
    "cut.hdr": lambda path: path.write_bytes(GOOD_MAP.read_bytes()[:GOOD_MAP.stat().st_size // 2]),
    "empty.hdr": lambda path: path.write_bytes(b""),
    "noise.exr": lambda path: path.write_bytes(np.random.default_rng(1).bytes(4096)),
    "noise.pfm": lambda path: path.write_bytes(b"PF\n4 4\n-1.0\n" + np.random.default_rng(2).bytes(100)),
    "huge.pfm": lambda path: path.write_bytes(b"PF\n99999 99999\n-1.0\n"),
    "folder.hdr": lambda path: path.mkdir(),
    "missing.hdr": lambda path: None,
}
# texture images beside each case's scene file (the maps above serve as textures too)
IMAGES = {
    "good.png": lambda path: PILImage.fromarray(
        np.random.default_rng(5).integers(0, 256, (4, 6, 3)).astype(np.uint8)).save(path),
    "grey.png": lambda path: PILImage.fromarray(np.full((3, 3), 200, np.uint8)).save(path),
    "cut.png": lambda path: path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00"),
    "text.jpg": lambda path: path.write_text("not an image"),
}
BATCH = 10          # cases a process renders (tests/fuzz_batch.py); a hypothesis example is a batch

ODD_NUMBERS = [0, -1, 1e-320, 1e-45, 3e38, 3.5e38, 1e300, -1e300, math.inf, -math.inf, math.nan,
               2**31, 2**31 - 1, -2**31, 10**400, 0.5, 1, 2, 179.9, 1e8]
ODD_VALUES = st.one_of(
    st.sampled_from(ODD_NUMBERS),
    st.booleans(),
    st.text(st.characters(exclude_categories=("Cs",)), max_size=8),   # TOML strings hold no surrogates
    st.just([]), st.just({}), st.just([[[[1]]]]),
    st.lists(st.sampled_from(ODD_NUMBERS), max_size=4),
)


def maybe(valid, odd=ODD_VALUES):
    """Mostly the valid value, one time in twenty an odd one (so that a scene holds a few at most
    and many scenes render)."""
    # hypothesis draws the ends of a range more often than its middle, so the odd case is a
    # middle value
    return st.integers(0, 19).flatmap(lambda k: odd if k == 7 else valid)


def vec3(low=-10.0, high=10.0):
    return maybe(st.lists(st.floats(low, high), min_size=3, max_size=3))


@st.composite
def textures(draw, depth=0):
    """An inline texture table: a bitmap of one of the images or maps, or a checkerboard, scale,
    mix or constant, with a uv transform; each field sometimes odd."""
    kind = draw(st.sampled_from(["bitmap", "bitmap", "checkerboard", "scale", "mix", "constant", "nosuch"]))
    t = {"type": draw(maybe(st.just(kind)))}
    if kind == "bitmap":
        good = ["good.png", "grey.png", "good.hdr"]
        t["file"] = draw(maybe(st.sampled_from(good), st.sampled_from(sorted(set(IMAGES) | set(MAPS) - set(good)))))
        if draw(st.booleans()):
            t["raw"] = draw(maybe(st.booleans()))
        if draw(st.booleans()):
            t["wrap"] = draw(maybe(st.sampled_from(["repeat", "mirror", "clamp"])))
        if draw(st.booleans()):
            t["filter"] = draw(maybe(st.sampled_from(["bilinear", "nearest"])))
    elif kind != "constant" and kind != "nosuch":
        inputs = {"checkerboard": ("color0", "color1"), "scale": ("tex", "scale"), "mix": ("tex1", "tex2", "amount")}
        for key in inputs[kind]:
            if draw(st.booleans()):
                t[key] = draw(maybe(st.floats(0, 1) if depth else st.one_of(st.floats(0, 1), textures(depth + 1))))
    else:
        t["value"] = draw(maybe(st.floats(0, 1)))
    if draw(st.booleans()):
        t[draw(st.sampled_from(["uv_scale", "uv_offset", "uv_rotate"]))] = draw(maybe(st.floats(-4, 4)))
    return t


def param_values(param):
    """Valid values of one material parameter, as its Param declares them (app/materials/bsdf.py);
    one that a texture may give (Param.texture) now and then a texture."""
    if param.kind == "bool":
        return st.booleans()
    if param.kind == "name":
        return st.sampled_from(sorted(param.names))
    high = min(param.high or 1e4, 1e4)
    if param.kind == "color":
        one = st.floats(param.low, high / 3)     # phong's rho_d + rho_s must stay <= 1
        values = st.one_of(one, st.lists(one, min_size=3, max_size=3))
    else:
        values = st.floats(max(param.low, 1e-3), high)
        values = st.one_of(values, st.sampled_from(sorted(param.names))) if param.names else values
    if param.texture:
        return st.integers(0, 5).flatmap(lambda k: textures() if k == 0 else values)
    return values


@st.composite
def materials(draw):
    """A material of any type with a random subset of its parameters, each sometimes odd; or,
    now and then, a type that does not exist."""
    kind = draw(st.sampled_from(MATERIAL_TYPES + ["nosuch"]))
    m = {"type": draw(maybe(st.just(kind)))}
    if kind == "emitter":
        m["Le"] = draw(maybe(st.floats(0, 100)))
    elif kind == "twosided":
        m["bsdf"] = draw(maybe(materials()))
    elif kind in FILE_TYPES:
        for param in FILE_TYPES[kind].params:       # the required ones, and some of the others
            if param.default is None or draw(st.booleans()):
                m[param.name] = draw(maybe(param_values(param)))
    if kind not in ("twosided", "nosuch") and draw(st.integers(0, 4)) == 0:
        key = draw(st.sampled_from(["opacity", "normal_map", "bump_map", "Le"]))
        m[key] = draw(maybe(st.one_of(textures(), st.floats(0, 1))))
        if key == "bump_map" and draw(st.booleans()):
            m["bump_scale"] = draw(maybe(st.floats(-2, 2)))
        if key in ("normal_map", "bump_map") and draw(st.booleans()):
            m["perturbation"] = draw(maybe(st.sampled_from(["mitsuba", "pbrt"])))
    if draw(st.integers(0, 19)) == 7:
        m[draw(st.sampled_from(["Le", "twosided", "bogus"]))] = draw(ODD_VALUES)
    return m


@st.composite
def scenes(draw):
    scene = {
        "camera": {"eye": draw(vec3()), "look_at": draw(vec3(-1, 1)), "up": draw(vec3(-1, 1)),
                   "vfov": draw(maybe(st.floats(1, 179)))},
        "environment": {"color": draw(maybe(st.floats(0, 2))), "intensity": draw(maybe(st.floats(0, 4))),
                        "rotation": draw(maybe(st.floats(-720, 720)))},
        "map": draw(st.sampled_from([None, None, None] + sorted(MAPS))),
        "render": {"max_depth": draw(maybe(st.integers(0, 16))), "spp": draw(maybe(st.integers(1, 4))),
                   "russian_roulette": draw(maybe(st.sampled_from(["throughput", "albedo", "off"]))),
                   "nee": draw(maybe(st.booleans()))},
        "spheres": [{"center": draw(vec3()), "radius": draw(maybe(st.floats(0.01, 5))),
                     "material": draw(materials())} for _ in range(draw(st.integers(1, 3)))],
    }
    if draw(st.booleans()):
        scene["meshes"] = [{"vertices": draw(maybe(st.lists(st.lists(st.floats(-5, 5), min_size=3, max_size=3),
                                                             min_size=3, max_size=6))),
                            "faces": draw(maybe(st.just([[0, 1, 2]]))),
                            "material": draw(materials())}]
        if draw(st.booleans()):
            scene["meshes"][0]["uvs"] = draw(maybe(st.lists(st.lists(st.floats(-2, 2), min_size=2, max_size=2),
                                                            min_size=3, max_size=6)))
    environment_map = scene.pop("map")
    if environment_map is not None:       # in place of the constant colour, as the format has it
        del scene["environment"]["color"]
        scene["environment"]["map"] = environment_map
    for section in list(scene):            # whole sections sometimes dropped or replaced
        choice = draw(st.integers(0, 29))
        if choice == 13:
            del scene[section]
        elif choice == 14:
            scene[section] = draw(ODD_VALUES)
    return scene


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if v != v else "inf" if v == math.inf else "-inf" if v == -math.inf else repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)   # a TOML basic string is a JSON string (no surrogate escapes)
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    return "[" + ", ".join(toml_value(x) for x in v) + "]"


def toml_text(scene: dict) -> str:
    """The scene as TOML: tables for the dict sections, arrays of tables for spheres and meshes."""
    lines, top = [], []
    for key, value in scene.items():
        if isinstance(value, dict):
            lines.append(f"[{key}]")
            lines += [f"{k} = {toml_value(v)}" for k, v in value.items()]
        elif key in ("spheres", "meshes") and isinstance(value, list) and value \
                and all(isinstance(s, dict) for s in value):
            for entry in value:
                lines.append(f"[[{key}]]")
                lines += [f"{k} = {toml_value(v)}" for k, v in entry.items()]
        else:
            top.append(f"{key} = {toml_value(value)}")
    return "\n".join(top + lines) + "\n"


DEVICE = os.environ.get("PATHTRACE_TEST_DEVICE", "cpu")


def render_case(folder: Path, scene: Path) -> dict:
    """The batch case that renders `scene` in `folder` as `pathtrace render` does."""
    return {"cwd": str(folder), "argv": ["render", str(scene), "-o", str(folder / "out.exr"), "--size", "8x6", "-q",
                                         "--device", DEVICE]}


def check_batch(tmp_path: Path, items: list, write):
    """Renders a case per item in one batch, each in a folder of its own, and checks each
    (check_case). write(folder, item) writes the case's files into its folder and returns (the
    scene's path, the folder's files before the scene was written, what a failure shows, the
    fuzzed file an error must name or None)."""
    with tempfile.TemporaryDirectory(dir=tmp_path) as root:
        cases = []
        for k, item in enumerate(items):
            folder = Path(root) / f"case{k}"
            folder.mkdir()
            cases.append((folder, *write(folder, item)))
        results = run_batch([render_case(folder, path) for folder, path, *_ in cases], Path(root))
        for (folder, path, before, shown, named), result in zip(cases, results):
            check_case(folder, path, before, shown, result, named)


@settings(max_examples=30 // BATCH, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                          HealthCheck.too_slow])
@given(batch=st.lists(scenes(), min_size=BATCH, max_size=BATCH))
def test_scene_files_render_finite_pixels_or_are_refused_in_one_line(tmp_path, batch):
    def write(folder, scene):
        for name, make in {**MAPS, **IMAGES}.items():
            make(folder / name)
        before = sorted(p.name for p in folder.iterdir())
        path = folder / "fuzzed.toml"
        path.write_text(toml_text(scene))
        return path, before, path.read_text(), None
    check_batch(tmp_path, batch, write)


def check_case(folder: Path, path: Path, before: list, shown: str, result: dict, named: str = None):
    """The outcome of rendering scene `path` in `folder` (whose files were `before`, the scene
    written since; `result` tests/fuzz_batch.py's): exit 0 with an image of finite pixels, or exit
    1 with one error line that names the scene (or `named`, the fuzzed file it refers to); nothing
    else on standard error, no traceback, and no file left behind. `shown` is what a failure
    prints of the case."""
    status, err = result["status"], result["stderr"]
    event(f"exit {status}")           # shown by pytest --hypothesis-show-statistics
    case = f"{shown}\nexit {status}, standard error:\n{err}{result['traceback']}"
    assert not result["traceback"] and status in (0, 1), case     # 2: a usage error
    lines = err.splitlines()
    assert all(line.startswith(("device: ", "wrote ", "pathtrace: warning: ", "pathtrace: error: "))
               for line in lines), case
    errors = [line for line in lines if line.startswith("pathtrace: error: ")]
    left = sorted(set(p.name for p in folder.iterdir()) - set(before))
    if status == 1:
        assert len(errors) == 1 and (str(path) in errors[0] or (named or str(path)) in errors[0]), case
        assert left == [path.name], case
    else:
        assert not errors and left == sorted([path.name, "out.exr"]), case
        assert np.all(np.isfinite(read_hdr(folder / "out.exr", "test"))), case
