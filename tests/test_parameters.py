"""The parameter declarations (app/parameters.py): how a reader's values are read through them, and
the tables of docs/scene-format.md, which must be what the declarations generate."""

import numpy as np
import pytest

from pathtrace.lights import DELTA_LIGHTS
from pathtrace.materials import BSDFS
from pathtrace.parameters import FRAME, SAME, Parameter, by_format, out_of_range, read
from pathtrace.scene import format_tables
from pathtrace.textures import Texture


def test_the_docs_tables_are_the_declarations():
    """Run `python -m pathtrace.scene.format_tables` after changing a type's parameters."""
    text = format_tables.DOC.read_text()
    assert format_tables.update(text) == text
    for kind in ("lights", "materials", "textures", "media"):
        assert f"<!-- parameters: {kind} -->" in text


def test_a_format_reads_its_names_defaults_and_conversions():
    params = (Parameter("a", "number", 1.0, pbrt="x", pbrt_default=2.0, from_pbrt=lambda v, given: v * given["k"]),
              Parameter(None, "number", pbrt="k", pbrt_default=10.0),
              Parameter("b", "point", mitsuba="b", mitsuba_default=FRAME),
              Parameter("c", "number", 3.0, mitsuba="cc"))
    given = {"x": 4.0}
    assert read(params, "pbrt", lambda p, name: given.get(name)) == {"a": 40.0}
    assert read(params, "pbrt", lambda p, name: None) == {"a": 20.0}    # the format's default, converted
    values = read(params, "mitsuba", lambda p, name: {"cc": 5.0}.get(name))
    assert values == {"b": FRAME, "c": 5.0}                            # a left as the type's own default
    assert read(params, "toml", lambda p, name: {"a": 7.0}.get(name)) == {"a": 7.0}
    assert params[0].default_in("toml") is SAME


def test_one_range_check_serves_every_kind_and_a_texture_by_its_bounds():
    params = (Parameter("n", "integer", 1, low=1, high=8), Parameter("x", "number", 0.5, low=0.0, high=1.0),
              Parameter("c", "color", 0.5, low=0.0), Parameter("free", "number", 0.0))
    assert out_of_range(params, {"n": 8, "x": 1.0, "c": [0, 2, 3], "free": -1e30}) is None
    assert str(out_of_range(params, {"n": 9})) == "n: must be in 1..8, got 9"
    # a file's integer may be of any size (Mitsuba's are read by int()): compared, not a traceback
    assert str(out_of_range(params, {"n": 10 ** 23})) == f"n: must be in 1..8, got {10 ** 23}"
    assert str(out_of_range(params, {"x": float("nan")})) == "x: must lie in [0, 1], got nan"
    assert str(out_of_range(params, {"c": [1, -2, 3]})) == "c: must lie in [0, inf), got from -2 to 3"
    # compared in float32, as the kernels hold values: a bound read back from a row is within it,
    # and what float32 cannot hold is not
    tiny = (Parameter("t", "number", 0.5, low=1e-6, high=1e3),)
    assert out_of_range(tiny, {"t": float(np.float32(1e-6))}) is None and float(np.float32(1e-6)) < 1e-6
    assert str(out_of_range(params, {"c": [1, 1, 1e39]})) == "c: must lie in [0, inf), got from 1 to 1e+39"
    assert str(out_of_range(params, {"x": 10 ** 400})) == "x: must lie in [0, 1], got inf"
    # a number's texture by its luminance, as the kernels read it; a colour's by its channels
    red = Texture("constant", {"value": np.array([5.0, 0.0, 0.0]), "to_uv": np.eye(3)})
    assert str(out_of_range(params, {"x": red})) == "x: must lie in [0, 1], got 1.063"
    assert out_of_range(params, {"c": red}) is None


def test_every_type_a_format_names_is_found_by_that_name():
    assert by_format(DELTA_LIGHTS.values(), "pbrt") == {
        c.formats["pbrt"]: c for c in DELTA_LIGHTS.values() if "pbrt" in c.formats}
    mitsuba = by_format(BSDFS.values(), "mitsuba")
    assert mitsuba["diffuse"] is BSDFS["diffuse"] and "coateddiffuse" not in mitsuba
    # a BSDF Mitsuba has takes pathtrace's names there unless one is declared (diffuse's reflectance)
    assert {p.mitsuba for p in BSDFS["diffuse"].params} == {"reflectance"}
    assert all(p.mitsuba == p.name for p in BSDFS["plastic"].params)


def test_a_light_reads_the_same_from_each_format_it_has():
    """A spot of pbrt-v4's cone and Mitsuba's to_world: the same light as the TOML values say."""
    spot = DELTA_LIGHTS["spot"]
    values = read(spot.parameters, "pbrt", lambda p, name: {"from": np.array([0, 2.0, 0]), "to": np.zeros(3),
                                                            "coneangle": 40.0, "conedeltaangle": 10.0}.get(name))
    light = spot.from_values(values)
    assert np.allclose(light.direction, [0, -1, 0]) and light.cutoff_angle == 40 and light.beam_width == 30
    assert light.falloff == "smoothstep" and np.allclose(light.intensity, 1)


def test_the_render_settings_read_each_format_s_defaults_and_conversions():
    """A file without a film, sampler or integrator renders at its renderer's defaults; Mitsuba's
    max_depth -1 is unlimited, pbrt-v4's maxdepth counts bounces, and a bad one names its field."""
    from pathtrace.scene import settings
    mitsuba, pbrt = settings.defaults("mitsuba"), settings.defaults("pbrt")
    assert (mitsuba.width, mitsuba.height, mitsuba.spp, mitsuba.max_depth) == (768, 576, 4, 0)
    assert (pbrt.width, pbrt.height, pbrt.spp, pbrt.max_depth, pbrt.light_sampler) == (1280, 720, 16, 6, "auto")
    given = {"maxdepth": 3, "lightsampler": "uniform"}
    assert read(settings.Integrator.parameters, "pbrt", lambda p, name: given.get(name)) == {
        "max_depth": 4, "light_sampler": "power"}
    given = {"lightsampler": "exhaustive"}        # pbrt-v4 takes it: pathtrace's light tree
    assert read(settings.Integrator.parameters, "pbrt", lambda p, name: given.get(name))["light_sampler"] == "auto"
    for fmt, value, message in (("mitsuba", 0, "^max_depth: 0 renders nothing"), ("pbrt", -1, "^maxdepth: must be in")):
        with pytest.raises(ValueError, match=message):
            read(settings.Integrator.parameters, fmt, lambda p, name: value if name in ("max_depth", "maxdepth") else None)
