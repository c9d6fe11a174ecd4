"""Mitsuba 3's principled BSDF (kernels/bsdfs/principled.cl): its value and density against
Mitsuba's own at thousands of pairs of directions (tests/references/bsdfs/principled.npz, made by
scripts/make_principled_evals.py) and the parameters' checks in every reader (its sampling, weights
and reciprocity, by its examples, in tests/test_bsdfs.py). The render of
tests/scenes/principled.xml against Mitsuba's is in test_reference.py."""

import json
from pathlib import Path

import numpy as np
import pytest
from pyopencl import cltypes

from pathtrace.errors import UserError
from pathtrace.materials import BSDFS, TRANSMISSIVE, pack
from tests.test_bsdfs import evaluate

EVALS = np.load(Path(__file__).parent / "references" / "bsdfs" / "principled.npz")
CASES = json.loads(str(EVALS["cases"]))


@pytest.mark.parametrize("case", range(len(CASES)))
def test_value_and_density_are_mitsubas(kernels, case):
    """f and pdf at every stored pair, as Mitsuba 3 evaluates them (to float32 rounding): the
    lobes, their weights, the Fresnel blend, anisotropy, flatness, transmission from both sides."""
    m = pack("principled", CASES[case])
    pick = EVALS["case"] == case
    wo, wi, f_ref, pdf_ref = EVALS["wo"][pick], EVALS["wi"][pick], EVALS["f"][pick], EVALS["pdf"][pick]
    for o in np.unique(wo, axis=0):
        at = np.all(wo == o, axis=1)
        f, pdf = evaluate(kernels, m, cltypes.make_float4(*o, 0), wi[at])
        np.testing.assert_allclose(f, f_ref[at], rtol=2e-4, atol=1e-6)
        np.testing.assert_allclose(pdf, pdf_ref[at], rtol=2e-4, atol=1e-6)
    assert np.count_nonzero(f_ref[:, 0] > 0) > len(f_ref) // 3       # the pairs see the lobes


def test_specular_is_the_ior_mitsuba_derives_and_transmission_makes_it_two_faced():
    values = BSDFS["principled"].complete({"specular": 0.5})
    assert values["eta"] == pytest.approx(1.5) and "specular" not in values
    # specular 0 is IOR 1, which Mitsuba moves off 1 for a transmitting material
    assert BSDFS["principled"].complete({"specular": 0.0})["eta"] == 1.0
    assert BSDFS["principled"].complete({"specular": 0.0, "spec_trans": 0.5})["eta"] == pytest.approx(
        2 / (1 - np.sqrt(0.08e-3)) - 1)
    assert not pack("principled", {})["flags"][0] & TRANSMISSIVE
    assert pack("principled", {"spec_trans": 0.3})["flags"][0] & TRANSMISSIVE


@pytest.mark.parametrize("body,problem", [
    ('metallic = 1.5', "metallic"),
    ('roughness = -0.1', "roughness"),
    ('eta = 1.5, specular = 0.5', "eta or specular"),
    ('eta = 0.0', "eta"),
    ('spec_trans = 0.5, twosided = true', "two-sided"),
    ('anisotropic = nan', "anisotropic"),
])
def test_bad_parameters_are_one_line_naming_the_field(tmp_path, body, problem):
    from pathtrace.scene import load_scene
    path = tmp_path / "s.toml"
    path.write_text(f'[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = {{ type = "principled", {body} }}\n')
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    assert problem in str(e.value) and "\n" not in str(e.value)


def test_mitsuba_files_map_principled_and_refuse_its_bad_values(tmp_path):
    from pathtrace.scene import load_scene

    def scene(bsdf):
        path = tmp_path / "s.xml"
        path.write_text(f'<scene version="3.0.0"><shape type="sphere">{bsdf}</shape></scene>')
        return load_scene(str(path))
    m = scene('<bsdf type="principled"><rgb name="base_color" value="0.2, 0.4, 0.6"/>'
              '<float name="specular" value="0.8"/><float name="spec_trans" value="0.3"/></bsdf>').materials.get(0)
    assert m.type == "principled" and m.params["eta"] == pytest.approx(2 / (1 - np.sqrt(0.064)) - 1)
    np.testing.assert_allclose(m.params["base_color"], [0.2, 0.4, 0.6])
    for bad in ('<float name="clearcoat" value="2"/>', '<float name="eta" value="1.4"/><float name="specular" value="0.5"/>'):
        with pytest.raises(UserError) as e:
            scene(f'<bsdf type="principled">{bad}</bsdf>')
        assert "\n" not in str(e.value)
    with pytest.raises(UserError, match="transmits"):
        scene('<bsdf type="twosided"><bsdf type="principled"><float name="spec_trans" value="1"/></bsdf></bsdf>')
