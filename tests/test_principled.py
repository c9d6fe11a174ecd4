"""Mitsuba 3's principled BSDF (kernels/bsdfs/principled.cl): its value and density against
Mitsuba's own at thousands of pairs of directions (tests/references/bsdfs/principled.npz, made by
scripts/make_principled_evals.py), its sampling against its density over the whole sphere, the
weights against f |cos| / pdf, and the parameters' checks in every reader. The render of
tests/scenes/principled.xml against Mitsuba's is in test_reference.py."""

import json
from pathlib import Path

import numpy as np
import pytest
from pyopencl import cltypes

from pathtrace.errors import UserError
from pathtrace.materials import BSDFS, TRANSMISSIVE, pack
from tests.test_bsdfs import direction, evaluate, sample
from tests.test_materials import sphere_grid
from tests.test_sampling import chi_square

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


SAMPLED = {
    "coated-sheen": {"base_color": [0.8, 0.3, 0.1], "roughness": 0.3, "metallic": 0.4, "spec_tint": 0.6,
                     "sheen": 0.8, "clearcoat": 0.9, "clearcoat_gloss": 0.7},
    "anisotropic-metal": {"base_color": [0.95, 0.7, 0.3], "roughness": 0.5, "anisotropic": 0.8, "metallic": 1.0},
    "glass": {"base_color": [0.9, 0.8, 0.6], "roughness": 0.2, "spec_trans": 0.8, "eta": 1.45},
    "everything": {"base_color": [0.3, 0.6, 0.2], "roughness": 0.6, "spec_trans": 0.5, "metallic": 0.2,
                   "specular": 0.7, "clearcoat": 0.5, "flatness": 0.6, "anisotropic": 0.4, "sheen": 0.5,
                   "clearcoat_sampling_rate": 3.0, "diffuse_reflectance_sampling_rate": 0.5},
}


# from outside, and from inside where the material transmits (an opaque one is never seen so)
SAMPLED_FROM = [(name, theta) for name in SAMPLED
                for theta in (20, 70) + ((125,) if SAMPLED[name].get("spec_trans") else ())]


@pytest.mark.parametrize("name,theta", SAMPLED_FROM)
def test_sampling_follows_the_density_over_the_sphere(kernels, name, theta):
    """The directions drawn follow pdf_principled over the whole sphere, and it integrates to
    the share of draws that gave one."""
    m = pack("principled", SAMPLED[name])
    wo = direction(theta, 30)
    wi, weight = sample(kernels, m, wo, seed=theta)
    ok = weight[:, 3] == 1
    nz, nphi, sub = 32, 16, 40
    grid, cell = sphere_grid(nz * sub, nphi * sub)
    _, pdf = evaluate(kernels, m, wo, grid[:, [0, 2, 1]])        # the pole along y, off the lobes
    expected = (pdf * cell).reshape(nz, sub, nphi, sub).sum(axis=(1, 3)) * len(wi)
    counts, _, _ = np.histogram2d(wi[ok, 1], np.arctan2(wi[ok, 2], wi[ok, 0]),
                                  [np.linspace(-1, 1, nz + 1), np.linspace(-np.pi, np.pi, nphi + 1)])
    assert expected.sum() == pytest.approx(ok.sum(), rel=0.01)
    assert chi_square(counts.ravel(), expected.ravel()) > 1e-3


@pytest.mark.parametrize("name", list(SAMPLED))
def test_weights_are_f_cos_over_the_reported_pdf(kernels, name):
    m = pack("principled", SAMPLED[name])
    for theta in (35, 140) if m["flags"][0] & TRANSMISSIVE else (35,):
        wo = direction(theta, 30)
        wi, weight = sample(kernels, m, wo, count=4000, seed=5)
        ok = weight[:, 3] == 1
        f, pdf = evaluate(kernels, m, wo, wi[ok])
        np.testing.assert_allclose(wi[ok, 3], pdf, rtol=2e-4)
        np.testing.assert_allclose(weight[ok, :3], f * np.abs(wi[ok, 2:3]) / pdf[:, None], rtol=2e-3, atol=1e-6)


@pytest.mark.parametrize("name", list(SAMPLED))
def test_reflection_is_reciprocal(kernels, name):
    """Every reflecting lobe is symmetric in its two directions (the diffuse lobe's Schlick
    weights, the sheen's cos_d, the specular's and the clearcoat's F at wo.h = wi.h)."""
    m = pack("principled", SAMPLED[name])
    wo = direction(40, 30)
    wi, weight = sample(kernels, m, wo, count=2000, seed=9)
    up = (weight[:, 3] == 1) & (wi[:, 2] > 0)
    forward, _ = evaluate(kernels, m, wo, wi[up])
    wo_vec = np.array([wo["x"], wo["y"], wo["z"]])
    for k, w in enumerate(wi[up][:50]):
        back, _ = evaluate(kernels, m, cltypes.make_float4(*w[:3], 0), wo_vec[None])
        np.testing.assert_allclose(back[0], forward[k], rtol=1e-3, atol=1e-7)


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
