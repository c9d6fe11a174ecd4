"""The materials of the field (kernels/bsdfs/: conductor, roughconductor, dielectric,
thindielectric, plastic, roughplastic, diffusetransmission, the coated ones) against their
closed forms and furnaces. What every type owes (sampling against its pdf, the pdf's
normalisation, the sample weight, reciprocity, energy) is tested for every registered type, by
its examples, in tests/test_bsdfs.py; images against Mitsuba 3 are in
test_reference.py."""

import numpy as np
import pytest
from pyopencl import cltypes

from pathtrace.materials import BSDFS, Material, pack
from pathtrace.rendering.renderer import Renderer
from pathtrace.materials.microfacet import TABLE_COSINES, rough_coating, rough_dielectric_albedo
from pathtrace.materials.optics import diffuse_fresnel_reflectance, fresnel_dielectric
from tests.test_bsdfs import direction, evaluate, hemisphere_grid, sample
from tests.test_integrator import furnace_scene, render


def material(name, **params):
    return pack(name, BSDFS[name].resolve(params))


@pytest.mark.parametrize("theta", [0, 40, 75])
def test_plastic_albedo_is_the_closed_form(kernels, theta):
    """With F_dr exact, the linear plastic's albedo is F(wo) specular + (1 - F(wo)) rho: the
    coating's reflection plus all the light it lets in, returned with the base's albedo (the
    reciprocity 1 - F_dr(eta) = eta^2 (1 - F_dr(1/eta)) cancels every other factor)."""
    rho, spec, eta = np.array([0.8, 0.4, 0.1]), np.array([1.0, 0.9, 0.5]), 1.5
    m = material("plastic", diffuse_reflectance=rho, specular_reflectance=spec, int_ior=eta, ext_ior=1.0)
    wi, weight = sample(kernels, m, direction(theta), seed=theta + 2)
    f_o = fresnel_dielectric(np.cos(np.radians(theta)), eta)
    expected = f_o * spec + (1 - f_o) * rho
    mean, err = weight[:, :3].mean(axis=0), weight[:, :3].std(axis=0) / np.sqrt(len(weight))
    assert np.all(np.abs(mean - expected) < 5 * err + 1e-3), (mean, expected)


@pytest.mark.parametrize("alpha", [0.05, 0.3, 0.8])
@pytest.mark.parametrize("k", [2, 9, 15])
def test_rough_coating_reflects_what_the_host_quadrature_says(kernels, alpha, k):
    """Over a black base, roughplastic's albedo is its coating's reflectance alone: the kernel's
    microfacet sampling and the host's quadrature (which also gives the tabulated transmittance,
    from the same normals) agree; reflection and transmission sum to at most 1."""
    m = material("roughplastic", diffuse_reflectance=0.0, alpha=alpha, int_ior=1.5, ext_ior=1.0)
    cos_o = TABLE_COSINES[k]
    reflected, transmitted = rough_dielectric_albedo([cos_o], alpha, 1.5)
    assert transmitted[0] == pytest.approx(m["table"][0, k], rel=1e-5)
    assert reflected[0] + transmitted[0] <= 1.0 + 1e-6
    wi, weight = sample(kernels, m, direction(np.degrees(np.arccos(cos_o))), seed=k)
    mean, err = weight[:, 0].mean(), weight[:, 0].std() / np.sqrt(len(weight))
    assert abs(mean - reflected[0]) < 5 * err + 2e-3, (mean, reflected[0])


def test_rough_coating_tends_to_the_smooth_one():
    """As alpha -> 0 the rough coating's transmittance tends to 1 - F, and its internal
    reflectance to the smooth coating's by the same (Mitsuba's 64-point) rule, which stays
    within 0.015 of the exact F_dr."""
    table, inside = rough_coating(1e-3, 1.5)
    np.testing.assert_allclose(table[4:], 1.0 - fresnel_dielectric(TABLE_COSINES[4:], 1.5), atol=2e-3)
    mu = np.maximum(1e-6, np.linspace(0, 1, 64))
    assert inside == pytest.approx(2 * np.mean(fresnel_dielectric(mu, 1 / 1.5) * mu), abs=2e-3)
    assert inside == pytest.approx(diffuse_fresnel_reflectance(1.0 / 1.5), abs=0.015)


def test_diffuse_fresnel_reciprocity():
    """1 - F_dr(eta) = eta^2 (1 - F_dr(1/eta)) (the relation behind the plastic closed form)."""
    for eta in (1.33, 1.5, 2.4):
        assert 1 - diffuse_fresnel_reflectance(eta) == pytest.approx(
            eta ** 2 * (1 - diffuse_fresnel_reflectance(1 / eta)), rel=1e-5)


FRESNEL = """
kernel void fresnel(float eta, global const float *cos_i, global float4 *out)
{
    int i = get_global_id(0);
    float cos_t, eta_ti;
    float r = fresnel_dielectric(cos_i[i], eta, &cos_t, &eta_ti);
    out[i] = (float4)(r, cos_t, eta_ti, 0.0f);
}
kernel void conductor(float4 eta, float4 k, global const float *cos_i, global float4 *out)
{
    int i = get_global_id(0);
    out[i] = (float4)(fresnel_conductor(cos_i[i], eta.xyz, k.xyz), 0.0f);
}
"""


def dielectric_fresnel(kernels, eta, cos_i):
    cos_i = np.asarray(cos_i, np.float32)
    out = np.zeros((len(cos_i), 4), np.float32)
    kernels(FRESNEL)("fresnel", len(cos_i), np.float32(eta), cos_i, out)
    return out


def conductor_fresnel(kernels, eta, k, cos_i):
    cos_i = np.asarray(cos_i, np.float32)
    out = np.zeros((len(cos_i), 4), np.float32)
    kernels(FRESNEL)("conductor", len(cos_i), cltypes.make_float4(*eta, 0), cltypes.make_float4(*k, 0), cos_i, out)
    return out[:, :3]


@pytest.mark.parametrize("eta", [1.33, 1.5, 2.4])
def test_dielectric_fresnel_closed_forms(kernels, eta):
    """Normal incidence ((eta - 1) / (eta + 1))^2 from either side; grazing incidence 1; from
    inside, total internal reflection beyond the critical angle asin(1 / eta); Snell's law."""
    out = dielectric_fresnel(kernels, eta, [1.0, -1.0, 1e-7])
    assert out[0, 0] == pytest.approx(((eta - 1) / (eta + 1)) ** 2, rel=1e-5)
    assert out[1, 0] == pytest.approx(((eta - 1) / (eta + 1)) ** 2, rel=1e-5)
    assert out[2, 0] == pytest.approx(1.0, abs=1e-5)
    critical = np.arcsin(1 / eta)
    inside = -np.cos([critical - 0.01, critical + 0.01, critical + 0.3])
    out = dielectric_fresnel(kernels, eta, inside)
    assert out[0, 0] < 1.0 and out[1, 0] == 1.0 and out[2, 0] == 1.0
    theta = np.radians(np.linspace(0, 89, 30))
    out = dielectric_fresnel(kernels, eta, np.cos(theta))
    np.testing.assert_allclose(np.sqrt(1 - out[:, 1] ** 2), np.sin(theta) / eta, atol=1e-5)
    assert np.all(out[:, 1] < 0)                    # the transmitted side is the other one
    np.testing.assert_allclose(out[:, 2], 1 / eta, rtol=1e-6)


def test_conductor_fresnel_closed_forms(kernels):
    """Normal incidence ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2); eta 0, k 1 (Mitsuba's `none`) a
    perfect mirror at every angle; k = 0 reduces to the dielectric's reflectance."""
    eta, k = np.array([0.14304, 0.37531, 1.442]), np.array([3.983, 2.3856, 1.6034])    # gold
    r0 = conductor_fresnel(kernels, eta, k, [1.0])[0]
    np.testing.assert_allclose(r0, ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2), rtol=1e-5)
    cos_i = np.linspace(0.01, 1, 50)
    np.testing.assert_allclose(conductor_fresnel(kernels, [0, 0, 0], [1, 1, 1], cos_i), 1.0, atol=1e-5)
    np.testing.assert_allclose(conductor_fresnel(kernels, [1.5, 1.5, 1.5], [0, 0, 0], cos_i)[:, 0],
                               fresnel_dielectric(cos_i, 1.5), atol=1e-5)
    assert np.all(conductor_fresnel(kernels, eta, k, [1e-4]) > 0.99)     # grazing


@pytest.mark.parametrize("theta", [0, 30, 60, 85])
def test_smooth_conductor_is_a_fresnel_mirror(kernels, theta):
    m = material("conductor", material="Cu")
    wi, weight = sample(kernels, m, direction(theta), count=64)
    t = np.radians(theta)
    np.testing.assert_allclose(wi[:, :3], np.tile([-np.sin(t), 0, np.cos(t)], (64, 1)), atol=1e-6)
    eta, k = np.array(BSDFS["conductor"].resolve({"material": "Cu"})["eta"]), \
        np.array(BSDFS["conductor"].resolve({"material": "Cu"})["k"])
    np.testing.assert_allclose(weight[:, :3], np.tile(conductor_fresnel(kernels, eta, k, [np.cos(t)])[0], (64, 1)), rtol=1e-6)
    assert np.all(weight[:, 3] == 2)


@pytest.mark.parametrize("theta,side", [(0, 1), (40, 1), (80, 1), (30, -1), (60, -1)])
def test_dielectric_reflects_with_the_fresnel_probability_and_refracts_by_snell(kernels, theta, side):
    """From outside (side 1) and inside (-1): reflection is chosen with probability R, with
    weight 1; refraction obeys Snell's law and carries (n_i / n_t)^2, the radiance scaling.
    From inside at 60 degrees (beyond the critical angle of 41.8) every draw reflects."""
    eta = 1.5
    m = material("dielectric", int_ior=eta, ext_ior=1.0)
    t = np.radians(theta)
    wo = cltypes.make_float4(np.sin(t), 0, side * np.cos(t), 0)
    wi, weight = sample(kernels, m, wo, count=200_000, seed=theta)
    reflected = wi[:, 2] * side > 0
    r = fresnel_dielectric(np.cos(t), eta if side > 0 else 1 / eta)
    n = len(wi)
    assert abs(reflected.mean() - r) < 5 * np.sqrt(r * (1 - r) / n) + 1e-6
    np.testing.assert_allclose(weight[reflected, :3], 1.0, rtol=1e-6)
    if r < 1:
        eta_ti = 1 / eta if side > 0 else eta
        refr = ~reflected
        np.testing.assert_allclose(np.hypot(wi[refr, 0], wi[refr, 1]), eta_ti * np.sin(t), atol=1e-5)
        np.testing.assert_allclose(weight[refr, :3], eta_ti ** 2, rtol=1e-5)
    assert np.all(weight[:, 3] == 2)


def test_thin_dielectric_passes_straight_through(kernels):
    eta, t = 1.5, np.radians(50)
    m = material("thindielectric", int_ior=eta, ext_ior=1.0)
    wi, weight = sample(kernels, m, cltypes.make_float4(np.sin(t), 0, np.cos(t), 0), count=200_000)
    through = wi[:, 2] < 0
    np.testing.assert_allclose(wi[through, :3], np.tile([-np.sin(t), 0, -np.cos(t)], (through.sum(), 1)), atol=1e-6)
    r = fresnel_dielectric(np.cos(t), eta)
    r = 2 * r / (1 + r)                 # the sheet's inner reflections summed
    assert abs((~through).mean() - r) < 5 * np.sqrt(r * (1 - r) / len(wi))
    np.testing.assert_allclose(weight[:, :3], 1.0)


def furnace(backend, mat: Material, spp=64, **settings):
    mean, var, _ = render(backend, furnace_scene(None, material=mat, **settings), spp)
    return mean, var


@pytest.mark.parametrize("mat", [Material("dielectric", {"int_ior": 1.5}),
                                 Material("dielectric", {"int_ior": 2.4, "ext_ior": 1.33}),
                                 Material("thindielectric", {"int_ior": 1.5}),
                                 Material("conductor", {}),
                                 Material("blendbsdf", {"weight": 0.4}, components=(
                                     Material("diffuse", {"rho_d": 1.0}), Material("conductor", {})))],
                         ids=["glass", "diamond-in-water", "thin", "mirror", "blend-of-white-and-mirror"])
@pytest.mark.parametrize("rr", ["throughput", "albedo"])
def test_lossless_materials_render_the_environment(backend, mat, rr):
    """A white furnace: a lossless sphere (glass: every path enters and leaves, the radiance
    scaling cancelling; a mirror of reflectance 1) in a uniform environment of radiance 1 is
    invisible, and so is a blend of a white diffuse and a mirror (light sampling where the
    diffuse one is taken, none at the mirror). Paths inside glass can be long; Russian roulette
    keeps the estimate unbiased."""
    values = {**{p.name: p.default for p in BSDFS[mat.type].params if p.kind != "name"}, **mat.params}
    mean, var = furnace(backend, Material(mat.type, values, components=mat.components), russian_roulette=rr)
    assert np.all(np.abs(mean - 1.0) < 5 * np.sqrt(var) + 2e-3), (mean.min(), mean.max())


def ggx_albedo_at_normal_incidence(alpha):
    """1 - (light reflected below the horizon), by quadrature of GGX with separable Smith
    shadowing, written out here independently of the kernels."""
    grid, cell = hemisphere_grid(2000, 1000)
    h = grid + [0, 0, 1]
    h /= np.linalg.norm(h, axis=1)[:, None]
    t = (h[:, 0] ** 2 + h[:, 1] ** 2) / alpha ** 2 + h[:, 2] ** 2
    d = 1 / (np.pi * alpha ** 2 * t * t)
    g1 = 2 / (1 + np.sqrt(1 + alpha ** 2 * (1 - grid[:, 2] ** 2) / grid[:, 2] ** 2))
    return float((d * g1 / 4).sum() * cell)      # f cos = D G1(wo) G1(wi) / 4, G1(wo) = 1


def test_rough_mirror_loses_the_light_its_microfacets_send_below(backend):
    """Single-scattering microfacets lose the light that would bounce between them: a rough
    perfect mirror in a white furnace renders its directional albedo, below 1; seen head-on (the
    image's centre) that is the closed form's 0.88 at alpha 0.3."""
    mean, var = furnace(backend, Material("roughconductor", {"eta": 0.0, "k": 1.0, "specular_reflectance": 1.0,
                                                             "alpha": 0.3}), spp=256)
    assert np.all(mean <= 1.0 + 5 * np.sqrt(var) + 1e-3)
    centre, centre_var = mean[15:17, 23:25].mean(), var[15:17, 23:25].mean() / 12
    assert abs(centre - ggx_albedo_at_normal_incidence(0.3)) < 5 * np.sqrt(centre_var) + 5e-3


# -- diffuse transmission (pbrt-v4's) --

def sphere_grid(nz, nphi):
    """Midpoints of a (z, phi) grid over the whole sphere; each cell has solid angle dz dphi."""
    z = (np.arange(nz) + 0.5) / nz * 2 - 1
    phi = (np.arange(nphi) + 0.5) / nphi * 2 * np.pi - np.pi
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    s = np.sqrt(1 - zz ** 2)
    return np.stack([s * np.cos(pp), s * np.sin(pp), zz], -1).reshape(-1, 3), (2 / nz) * (2 * np.pi / nphi)


@pytest.mark.parametrize("side", [1, -1])
@pytest.mark.parametrize("params", BSDFS["diffusetransmission"].examples)
def test_diffuse_transmission_is_r_over_pi_on_wos_side_and_t_over_pi_through(kernels, side, params):
    """From either side, eval is R / pi on wo's side and T / pi through, and the pdf the cosine's
    on each side, in proportion to the two (its sampling: tests/test_bsdfs.py)."""
    values = BSDFS["diffusetransmission"].complete(params)
    m, wo = material("diffusetransmission", **params), direction(30 if side > 0 else 150)
    grid, _ = sphere_grid(64, 32)
    f, pdf = evaluate(kernels, m, wo, grid)
    same = np.sign(grid[:, 2]) == side
    r, t = np.broadcast_to(values["reflectance"], 3), np.broadcast_to(values["transmittance"], 3)
    assert np.allclose(f[same], r / np.pi, rtol=1e-5)
    assert np.allclose(f[~same], t / np.pi, rtol=1e-5)
    share = np.where(same, r.max(), t.max()) / (r.max() + t.max())
    assert np.allclose(pdf, share * np.abs(grid[:, 2]) / np.pi, rtol=1e-4, atol=1e-7)


@pytest.mark.parametrize("r, t", [(0.3, 0.7), (0.5, 0.7)])
def test_a_ball_of_diffuse_transmission_in_a_white_furnace(backend, r, t):
    """A sphere of it under a uniform sky of radiance 1: its inside is lit by T through the
    surface and by R of its own light, L_in = T / (1 - R), and its outside sends out
    R + T L_in = R + T^2 / (1 - R) in every direction. R + T = 1 gives 1 (light that enters
    bounces around and leaves); R + T = 1.2, which pbrt-v4 renders as it is, gives 1.48."""
    scene = furnace_scene(None, material=Material("diffusetransmission", {"reflectance": r, "transmittance": t}))
    for nee in (False, True):
        mean, var, _ = render(backend, scene.with_settings(nee=nee, max_depth=40), 64)
        center = mean[8:24, 16:32]
        expected = r + t * t / (1 - r)
        assert abs(center.mean() - expected) < 5 * np.sqrt(var[8:24, 16:32].mean() / center.size) + 2e-3 * expected


def test_a_two_sided_transmissive_material_is_refused_in_every_reader(tmp_path):
    """A two-sided dielectric rendered white furnaces at 0.23 and 0.84: the integrator turned
    its frame round before it could transmit. Mitsuba 3 refuses the combination; so do the
    material table and each reader, in one line naming the field."""
    from pathtrace.errors import UserError
    from pathtrace.materials import MaterialTable
    from pathtrace.scene import load_scene
    with pytest.raises(ValueError, match="cannot be two-sided"):
        MaterialTable().add(Material("dielectric", BSDFS["dielectric"].complete({}), twosided=True))
    (tmp_path / "s.toml").write_text('[materials]\nglass = { type = "dielectric", twosided = true }\n'
                                     '[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = "glass"\n')
    with pytest.raises(UserError, match="materials.glass.twosided: a dielectric cannot be two-sided"):
        load_scene(str(tmp_path / "s.toml"))
    (tmp_path / "s.xml").write_text('<scene version="3.0.0"><shape type="sphere"><bsdf type="twosided">'
                                    '<bsdf type="roughdielectric"/></bsdf></shape>'
                                    '<shape type="sphere"><bsdf type="twosided"><bsdf type="thindielectric"/></bsdf>'
                                    '</shape></scene>')
    with pytest.raises(UserError, match="s.xml:1: .*twosided: a roughdielectric cannot be two-sided: it transmits"):
        load_scene(str(tmp_path / "s.xml"))


@pytest.mark.parametrize("alpha", [0.2, 0.5, 1.0])
def test_beckmann_normals_are_normalised_and_its_g1_is_walters(kernels, alpha):
    """Seen from the normal, the density of the sampled direction integrates to the share of
    Beckmann normals within 45 degrees of it (the others reflect below the horizon),
    1 - exp(-1 / alpha^2); and G1 is within 0.4 % of Smith's exact form for Beckmann, 1 / (1 +
    Lambda), Lambda = (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi)), a = 1 / (alpha tan theta)."""
    from scipy.special import erf
    m = material("roughconductor", alpha=alpha, distribution="beckmann")
    grid, cell = hemisphere_grid(1500, 64)
    _, pdf = evaluate(kernels, m, direction(0), grid)
    assert (pdf * cell).sum() == pytest.approx(1 - np.exp(-1 / alpha ** 2), abs=2e-3)
    for theta in (20, 50, 75, 85):
        t = np.radians(theta)
        # wi the mirror image of wo, so h = +z: f = D(z) G1(wo) G1(wi) / (4 cos^2), D(z) = 1 / (pi a^2),
        # F = 1 (no metal given: a perfect mirror), G1(wo) = G1(wi) by symmetry
        f, _ = evaluate(kernels, m, direction(theta), np.array([[-np.sin(t), 0, np.cos(t)]]))
        g1 = np.sqrt(f[0, 0] * 4 * np.cos(t) ** 2 * np.pi * alpha ** 2)
        a = 1 / (alpha * np.tan(t))
        exact = 1 / (1 + (erf(a) - 1) / 2 + np.exp(-a * a) / (2 * a * np.sqrt(np.pi)))
        assert g1 == pytest.approx(exact, rel=4e-3)


def test_only_scenes_with_beckmann_metals_compile_beckmann(tmp_path):
    """The distribution's branch cost GGX scenes 3-6 % on an H100: BECKMANN is defined for the
    programs of scenes that have a Beckmann roughconductor only."""
    from pathtrace.compiler.compiled import CompiledScene
    from pathtrace.scene import load_scene

    def defines(distribution):
        (tmp_path / "s.toml").write_text(f'[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = {{ type = '
                                         f'"roughconductor", alpha = 0.2, distribution = "{distribution}" }}\n')
        scene = load_scene(str(tmp_path / "s.toml"))
        return CompiledScene(scene).features(scene.settings, scene.camera).defines()
    assert "BECKMANN" in defines("beckmann") and "BECKMANN" not in defines("ggx")


def test_only_scenes_with_anisotropic_roughness_keep_tangents(tmp_path):
    """A tangent per hit (kernels/frame.cl) is compiled in for anisotropic roughness only; an
    alpha_v left out follows alpha."""
    from pathtrace.compiler.compiled import CompiledScene
    from pathtrace.scene import load_scene

    def compiled(params):
        (tmp_path / "s.toml").write_text(f'[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = {{ type = '
                                         f'"roughconductor", {params} }}\n')
        scene = load_scene(str(tmp_path / "s.toml"))
        c = CompiledScene(scene)
        return "ANISOTROPIC" in c.features(scene.settings, scene.camera).defines(), scene.materials.get(0).params
    anisotropic, params = compiled("alpha = 0.2, alpha_v = 0.05")
    assert anisotropic and params["alpha_v"] == pytest.approx(0.05)
    anisotropic, params = compiled("alpha = 0.3")
    assert not anisotropic and params["alpha_v"] == pytest.approx(0.3)


# -- rough glass --

ROUGH_GLASS = {f"roughdielectric-{k}": material("roughdielectric", **params)
              for k, params in enumerate(BSDFS["roughdielectric"].examples)}


@pytest.mark.parametrize("theta", [40, 140])
@pytest.mark.parametrize("name", list(ROUGH_GLASS))
def test_rough_glass_refraction_is_reciprocal_up_to_the_iors(kernels, name, theta):
    """f(wi, wo) / n(wi's side)^2 = f(wo, wi) / n(wo's side)^2 (Veach 1997, 5.2), at the
    directions drawn (reflection's plain reciprocity, the weights and the sampling are in
    tests/test_bsdfs.py)."""
    m, wo = ROUGH_GLASS[name], direction(theta, 30)
    wi, weight = sample(kernels, m, wo, count=4000, seed=3)
    ok = weight[:, 3] == 1
    f, _ = evaluate(kernels, m, wo, wi[ok])
    n_inside, n_outside = float(m["p0"][0][0]), float(m["p0"][0][1])
    wo_vec = np.array([wo["x"], wo["y"], wo["z"]])
    n = lambda z: n_outside if z > 0 else n_inside      # noqa: E731
    for k in np.flatnonzero(ok)[:40]:
        back, _ = evaluate(kernels, m, cltypes.make_float4(*wi[k, :3], 0), wo_vec[None])
        forward = f[np.flatnonzero(ok) == k][0]
        np.testing.assert_allclose(back[0] / n(wi[k, 2]) ** 2, forward / n(wo_vec[2]) ** 2, rtol=2e-3, atol=1e-7)


@pytest.mark.parametrize("theta", [0, 60, 85, 150])
@pytest.mark.parametrize("name", list(ROUGH_GLASS))
def test_rough_glass_albedo_is_what_sampling_estimates_and_at_most_one(kernels, name, theta):
    """The quadrature of f |cos| over the sphere, with radiance's (n_wo / n_wi)^2 undone on
    the refracted side, is the sample weights' mean with that factor undone too, and at most 1:
    what the microfacets do not reflect or refract (shadowed light) is lost, never gained."""
    m, wo = ROUGH_GLASS[name], direction(theta, 30)
    n_inside, n_outside = float(m["p0"][0][0]), float(m["p0"][0][1])
    n_wo = n_outside if wo["z"] > 0 else n_inside
    grid, cell = sphere_grid(2400, 480)
    grid = grid[:, [0, 2, 1]]                 # the pole along y, away from the lobes
    f, _ = evaluate(kernels, m, wo, grid)
    crossed = np.where(grid[:, 2] * wo["z"] < 0, (np.where(grid[:, 2] > 0, n_outside, n_inside) / n_wo) ** 2, 1.0)
    albedo = (f[:, 0] * np.abs(grid[:, 2]) * crossed).sum() * cell
    wi, weight = sample(kernels, m, wo, seed=theta + 1)
    crossed = np.where(wi[:, 2] * wo["z"] < 0, (np.where(wi[:, 2] > 0, n_outside, n_inside) / n_wo) ** 2, 1.0)
    w = np.where(weight[:, 3] == 1, weight[:, 0] * crossed, 0.0)
    assert abs(w.mean() - albedo) < 5 * w.std() / np.sqrt(len(w)) + 3e-3, (w.mean(), albedo)
    assert albedo <= 1.0 + 3e-3


# -- pbrt-v4's coateddiffuse --

def coated(**params):
    return material("coateddiffuse", **params)


def exact_coated_albedo(rho, eta, cos_o):
    """A smooth coating over a Lambertian base with nothing between them, every inner bounce
    followed: the coating's reflection F, plus what enters, (1 - F), returned by the base with
    albedo rho, of which 1 - F_dr(1 / eta) leaves through the coating and F_dr(1 / eta) goes
    back down: (1 - F) rho (1 - F_dr) / (1 - rho F_dr). (Mitsuba's nonlinear plastic.)"""
    f, f_dr = fresnel_dielectric(cos_o, eta), diffuse_fresnel_reflectance(1 / eta)
    return f + (1 - f) * rho * (1 - f_dr) / (1 - rho * f_dr)


@pytest.mark.parametrize("theta", [0, 45, 75])
def test_a_thin_smooth_coating_is_the_exact_plastic(kernels, theta):
    """With no layer between them (thickness 1e-6, albedo 0) and walks long enough to follow
    every bounce, pbrt-v4's random walk gives the closed form, sampling and evaluation alike."""
    rho, eta = np.array([0.8, 0.4, 0.1]), 1.5
    m, wo = coated(reflectance=rho, eta=eta, thickness=1e-6, maxdepth=100), direction(theta)
    expected = exact_coated_albedo(rho, eta, np.cos(np.radians(theta)))
    wi, weight = sample(kernels, m, wo, seed=theta + 5)
    mean, err = weight[:, :3].mean(axis=0), weight[:, :3].std(axis=0) / np.sqrt(len(weight))
    assert np.all(np.abs(mean - expected) < 5 * err + 2e-3), (mean, expected)
    grid, cell = hemisphere_grid(600, 300)
    f, _ = evaluate(kernels, m, wo, grid)
    diffuse = (f * grid[:, 2:3]).sum(axis=0) * cell
    delta = fresnel_dielectric(np.cos(np.radians(theta)), eta)
    np.testing.assert_allclose(diffuse + delta, expected, rtol=0.01)


@pytest.mark.parametrize("theta", [0, 40, 70])
def test_a_smooth_coating_over_a_mirror_is_the_series_of_its_reflections(kernels, theta):
    """Smooth coating, clear thin layer, smooth metal: a delta BSDF whose albedo is the coating's
    F plus what enters, (1 - F), reflected by the metal at the refracted angle (R_m) and let out
    by the coating (1 - F), or sent back down (F): F + (1 - F)^2 R_m / (1 - F R_m). The metal
    meets the coating, not air: R_m is that of its eta and k divided by the coating's IOR
    (pbrt-v4's CoatedConductorMaterial::GetBxDF)."""
    from pathtrace.materials.optics import CONDUCTORS
    eta, (m_eta, m_k) = 1.5, CONDUCTORS["Au"]
    m = material("coatedconductor", material="Au", interface_eta=eta, thickness=1e-6, maxdepth=100)
    assert m["flags"][0] & 2                        # MATERIAL_DELTA: light sampling is skipped
    cos_o = np.cos(np.radians(theta))
    cos_t = np.sqrt(1 - (1 - cos_o ** 2) / eta ** 2)
    f, r_m = fresnel_dielectric(cos_o, eta), complex_fresnel(cos_t, np.array(m_eta) / eta, np.array(m_k) / eta)
    expected = f + (1 - f) ** 2 * r_m / (1 - f * r_m)
    wi, weight = sample(kernels, m, direction(theta), count=40000, seed=theta)
    assert np.all(weight[:, 3] == 2)                 # every sample a delta
    mean, err = weight[:, :3].mean(axis=0), weight[:, :3].std(axis=0) / np.sqrt(len(weight))
    assert np.all(np.abs(mean - expected) < 5 * err + 1e-4), (mean, expected)


def complex_fresnel(cos_i, eta, k):
    """The unpolarised Fresnel reflectance of a conductor (pbrt-v4's FrComplex), independent of
    kernels/fresnel.cl."""
    n = eta + 1j * k
    sin2 = 1 - cos_i ** 2
    cos_t = np.sqrt(1 - sin2 / n ** 2)
    r_par = (n * cos_i - cos_t) / (n * cos_i + cos_t)
    r_perp = (cos_i - n * cos_t) / (cos_i + n * cos_t)
    return (np.abs(r_par) ** 2 + np.abs(r_perp) ** 2) / 2


def test_an_invisible_coating_over_a_rough_metal_is_the_rough_metal(kernels):
    """A coating of IOR 1.0001 over a thin clear layer neither reflects nor bends: the estimate is
    the bare GGX metal's f."""
    layered = material("coatedconductor", material="Cu", interface_eta=1.0001, thickness=1e-6, conductor_alpha=0.3,
                       nsamples=4)
    bare = material("roughconductor", material="Cu", alpha=0.3, distribution="ggx")
    grid, _ = hemisphere_grid(12, 12)
    for theta in (10, 50):
        f_layered, _ = evaluate(kernels, layered, direction(theta), grid)
        f_bare, _ = evaluate(kernels, bare, direction(theta), grid)
        np.testing.assert_allclose(f_layered, f_bare, rtol=0.02, atol=1e-4)


@pytest.mark.parametrize("kind,params", [("coateddiffuse", {"reflectance": [0.7, 0.3, 0.1], "alpha": 0.15}),
                                         ("coatedconductor", {"material": "Cu", "alpha": 0.1, "conductor_alpha": 0.25,
                                                              "albedo": 0.5, "thickness": 0.1})])
def test_coated_light_sampling_and_bsdf_sampling_agree(backend, kind, params):
    """A rough coated sphere under a sky and a lamp: the image with next-event estimation (its
    MIS weights read the estimated pdf) and the one without agree to within noise."""
    from pathtrace.scene.environment import Environment
    from pathtrace.scene.description import SceneBuilder
    from tests.stats import z_test
    b = SceneBuilder()
    b.add_sphere((0, 0, 0), 1.0, Material(kind, BSDFS[kind].complete(params)), "ball")
    b.add_sphere((2, 3, 2), 0.6, Material("black", emission=np.array([6.0, 6.0, 6.0])), "lamp")
    scene = b.build("coated", environment=Environment.constant((0.3, 0.35, 0.4))).with_settings(
        max_depth=4, russian_roulette="off")
    images = []
    for nee in (True, False):
        r = Renderer(backend, scene.with_settings(nee=nee), 24, 24)
        for _ in range(16):
            r.add_samples(64)
        r.finish()
        images.append((r.mean(), r.variance() / r.samples))
    ok, p, threshold = z_test(images[0][0], images[0][1], images[1][0], images[1][1], block=4)
    assert ok, f"smallest p-value {p:.3g} below {threshold:.3g}"
