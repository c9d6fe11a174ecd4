"""A scene-file fuzzer (#12): TOML files generated around the valid shape of a scene (every field
sometimes replaced by a value of another type, a huge or tiny or non-finite number, an empty or
nested container, or left out) must either render to finite pixels or be refused with one
UserError line that names the file. Never another exception, and never a NaN or infinite pixel.

It runs in-process on the tests' device, with a bounded number of examples per CI run and a
per-example deadline; a crash of the device or a hang would end the test run itself, loudly."""

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.errors import UserError
from app.renderer import Renderer
from app.scene import load_scene
from app.scene.toml_reader import FILE_TYPES, MATERIAL_TYPES

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


def param_values(param):
    """Valid values of one material parameter, as its Param declares them (app/materials/bsdf.py)."""
    if param.kind == "bool":
        return st.booleans()
    if param.kind == "name":
        return st.sampled_from(sorted(param.names))
    high = min(param.high or 1e4, 1e4)
    if param.kind == "color":
        one = st.floats(param.low, high / 3)     # phong's rho_d + rho_s must stay <= 1
        return st.one_of(one, st.lists(one, min_size=3, max_size=3))
    values = st.floats(max(param.low, 1e-3), high)
    return st.one_of(values, st.sampled_from(sorted(param.names))) if param.names else values


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
        for param in FILE_TYPES[kind].params:
            if draw(st.booleans()):
                m[param.name] = draw(maybe(param_values(param)))
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


@settings(max_examples=60, deadline=20000, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow])
@given(scene=scenes())
def test_a_scene_file_renders_finite_pixels_or_is_refused_in_one_line(backend, tmp_path, scene):
    path = tmp_path / "fuzzed.toml"
    path.write_text(toml_text(scene))
    try:
        loaded = load_scene(str(path))
        renderer = Renderer(backend, loaded, 8, 6)
        renderer.add_samples(2)
        image = renderer.mean()
    except UserError as e:
        message = str(e)
        assert str(path) in message and "\n" not in message, message
        return
    assert np.all(np.isfinite(image)), path.read_text()
