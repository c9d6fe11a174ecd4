"""Participating media (app/scene/media.py, kernels/media/, kernels/phase.cl, kernels/volume.cl): the
phase function against its density, the volumetric path tracer against closed forms
(transmittance, single scattering, white furnaces), and the media of the TOML, Mitsuba and
pbrt-v4 readers with their bad input. tests/test_reference.py compares three scenes with
Mitsuba 3's volpath (tests/scenes/media-*.xml)."""

import math

import numpy as np
import pytest
from pyopencl import cltypes

from pathtrace.cameras import OrthographicCamera, PerspectiveCamera
from pathtrace.compiler.compiled import compile_scene
from pathtrace.scene.environment import Environment
from pathtrace.errors import UserError
from pathtrace.device.features import Features
from pathtrace.lights import DirectionalLight
from pathtrace.materials import Material
from pathtrace.scene.media import Medium, MediumInterface
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
from pathtrace.scene.description import Mesh, SceneBuilder
from pathtrace.scene.meshes import mitsuba_cube
from tests.test_sampling import chi_square

MEDIA = Features(media=True)

SOURCE = """
kernel void hg_sample(float g, float4 wo, global const float4 *u, global float4 *out)
{
    int i = get_global_id(0);
    float pdf;
    float3 wi = sample_hg(g, wo.xyz, u[i].xy, &pdf);
    out[i] = (float4)(wi, pdf);
}
kernel void hg_eval(float g, float4 wo, global const float4 *wi, global float *out)
{
    int i = get_global_id(0);
    out[i] = eval_hg(g, wo.xyz, wi[i].xyz);
}
"""
WO = np.array([0.36, -0.48, 0.8])       # a unit direction, pointing back along the path


def hg(g, cos):
    """Henyey-Greenstein's density of the cosine between wo and wi (Mitsuba's and pbrt's form)."""
    return (1 - g * g) / (4 * np.pi * (1 + g * g + 2 * g * cos) ** 1.5)


@pytest.mark.parametrize("g", [-0.7, 0.0, 0.0005, 0.3, 0.9])
def test_hg_sampling_follows_its_density(kernels, g):
    """Chi-square over the cosine to the direction of travel and the azimuth about it: the
    sampled directions follow eval_hg, and each sample reports eval_hg as its pdf."""
    n = 400_000
    u = np.random.default_rng(1).random((n, 4), np.float32)
    out = np.zeros((n, 4), np.float32)
    kernels(SOURCE, MEDIA)("hg_sample", n, np.float32(g), cltypes.make_float4(*WO, 0), u, out)
    wi = out[:, :3].astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1, atol=1e-5)
    cos = wi @ WO
    np.testing.assert_allclose(out[:, 3], hg(g, cos), rtol=2e-3, atol=1e-6)
    # the azimuth about the direction of travel, in a frame of its own
    t = np.cross(WO, [0, 0, 1.0])
    t /= np.linalg.norm(t)
    b = np.cross(WO, t)
    phi = np.arctan2(wi @ b, wi @ t)
    c_edges = np.linspace(-1, 1, 41)
    p_edges = np.linspace(-np.pi, np.pi, 9)
    counts, _, _ = np.histogram2d(cos, phi, [c_edges, p_edges])
    # the density of cos(wo, wi) is 2 pi hg(cos); its integral over a bin in closed form
    lo, hi = c_edges[:-1], c_edges[1:]
    mass = (1 - g * g) / (2 * g) * ((1 + g * g + 2 * g * lo) ** -0.5 - (1 + g * g + 2 * g * hi) ** -0.5) \
        if g != 0 else (hi - lo) / 2
    expected = np.outer(mass, np.diff(p_edges) / (2 * np.pi)) * n
    assert chi_square(counts.ravel(), expected.ravel()) > 1e-3


@pytest.mark.parametrize("g", [-0.5, 0.0, 0.8])
def test_hg_integrates_to_one_over_the_sphere(kernels, g):
    z = (np.arange(4000) + 0.5) / 4000 * 2 - 1
    phi = (np.arange(64) + 0.5) / 64 * 2 * np.pi
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    s = np.sqrt(1 - zz ** 2)
    wi = np.stack([s * np.cos(pp), s * np.sin(pp), zz, np.zeros_like(zz)], -1).reshape(-1, 4).astype(np.float32)
    out = np.zeros(len(wi), np.float32)
    kernels(SOURCE, MEDIA)("hg_eval", len(wi), np.float32(g), cltypes.make_float4(0, 0, 1, 0), wi, out)
    assert abs(out.sum() * (2 / 4000) * (2 * np.pi / 64) - 1) < 1e-3


# -- closed forms, rendered --

def render(backend, scene, size, spp, nee=True):
    r = Renderer(backend, scene.with_settings(nee=nee), *size)
    for _ in range(spp // 64):
        r.add_samples(64)
    r.finish()
    return r.mean().astype(np.float64), r.variance().astype(np.float64) / r.samples


def within_noise(mean, var_of_mean, expected, z=4.5):
    """The mean over pixels of `mean` equals `expected` to within z standard errors (pixels
    are independent)."""
    m = mean.reshape(-1, 3).mean(axis=0)
    se = np.sqrt(var_of_mean.reshape(-1, 3).sum(axis=0)) / (mean.size // 3)
    assert np.all(np.abs(m - expected) <= z * se + 1e-6), f"{m} against {expected} (standard error {se})"


def medium_scene(boundary: str, medium: Medium, shape="cube", **build):
    """A shape of `boundary` material (null or dielectric) of side or radius 1 at the origin,
    filled with `medium`, seen from +z."""
    b = SceneBuilder()
    row = b.material(Material(boundary, {"int_ior": 1.33, "ext_ior": 1.0} if boundary == "dielectric" else {}))
    inside = MediumInterface(0, -1)
    if shape == "sphere":
        b.add_sphere((0, 0, 0), 1.0, row, "medium", inside)
    else:
        vertices, faces, _ = mitsuba_cube()
        b.add_mesh(Mesh("box", vertices.astype(np.float32), faces.astype(np.int32), None, row, media=inside))
    build.setdefault("camera", PerspectiveCamera((0, 0, 4), (0, 0, 0), (0, 1, 0), 40))
    build.setdefault("environment", Environment.constant((1, 1, 1)))
    return b.build("media", media=[medium], **build)


@pytest.mark.parametrize("nee", [False, True])
def test_transmittance_through_a_slab_is_beer_lambert(backend, nee):
    """An orthographic view through a cube of absorbing medium (albedo 0) of side 2 against a
    white sky: every pixel inside it is exp(-2 sigma_t), per channel."""
    sigma_t = np.array([0.2, 0.7, 1.5])
    camera = OrthographicCamera((0, 0, 4), (0, 0, 0), (0, 1, 0), height=1.5)
    scene = medium_scene("null", Medium.checked("ink", sigma_t, np.zeros(3)), camera=camera)
    mean, var = render(backend, scene, (16, 16), 256, nee)
    within_noise(mean, var, np.exp(-2 * sigma_t))


def test_single_scattering_of_a_thin_slab_under_a_sun(backend):
    """A slab of thickness h under a sun straight overhead (irradiance E), seen from straight
    above, paths of one scattering only (max_depth 2): the radiance back up is
    E sigma_s p(back) (1 - exp(-2 sigma_t h)) / (2 sigma_t), p(back) the phase function's
    value for light turned straight round: (1 - g) / (4 pi (1 + g)^2)."""
    h, g, E = 0.2, 0.4, 3.0
    sigma_s, sigma_a = np.array([0.5, 1.0, 2.0]), np.array([0.1, 0.3, 0.0])
    sigma_t = sigma_s + sigma_a
    b = SceneBuilder()
    row = b.material(Material("null"))
    vertices, faces, _ = mitsuba_cube()
    vertices = vertices * [50, h / 2, 50] + [0, h / 2, 0]
    b.add_mesh(Mesh("slab", vertices.astype(np.float32), faces.astype(np.int32), None, row,
                    media=MediumInterface(0, -1)))
    sun = DirectionalLight(np.array([0, -1.0, 0]), np.full(3, E))
    sun.check()
    camera = OrthographicCamera((0, 5, 0), (0, 0, 0), (0, 0, -1), height=1.0)
    scene = b.build("slab", media=[Medium.checked("haze", sigma_a, sigma_s, g)], camera=camera,
                    environment=Environment.constant((0, 0, 0)), lights=[sun]).with_settings(
        max_depth=2, russian_roulette="off")
    mean, var = render(backend, scene, (16, 16), 256)
    p_back = (1 - g) / (4 * math.pi * (1 + g) ** 2)
    within_noise(mean, var, E * sigma_s * p_back * (1 - np.exp(-2 * sigma_t * h)) / (2 * sigma_t))


@pytest.mark.parametrize("boundary,shape", [("null", "sphere"), ("dielectric", "sphere"), ("dielectric", "cube")])
@pytest.mark.parametrize("nee", [False, True])
def test_a_medium_of_albedo_one_in_a_white_furnace_is_one(backend, boundary, shape, nee):
    """Nothing absorbs: behind a null or glass boundary, a forward-scattering medium whose
    extinction differs threefold between channels returns all the light it receives."""
    medium = Medium.from_albedo("cloud", (3.0, 1.0, 0.4), 1.0, 0.6)
    scene = medium_scene(boundary, medium, shape).with_settings(max_depth=0, russian_roulette="throughput")
    mean, var = render(backend, scene, (16, 16), 256, nee)
    within_noise(mean, var, np.ones(3))


def test_the_camera_inside_a_medium_sees_it(backend):
    """A camera inside an absorbing medium that fills a large box looks at a white sky through
    4 units of it: exp(-4 sigma_t)."""
    sigma_t = np.array([0.05, 0.2, 0.4])
    b = SceneBuilder()
    row = b.material(Material("null"))
    vertices, faces, _ = mitsuba_cube()
    b.add_mesh(Mesh("room", (vertices * 4).astype(np.float32), faces.astype(np.int32), None, row,
                    media=MediumInterface(0, -1)))
    camera = OrthographicCamera((0, 0, 0), (0, 0, -1), (0, 1, 0), height=0.5)
    scene = b.build("inside", media=[Medium.checked("ink", sigma_t, np.zeros(3))], camera=camera,
                    environment=Environment.constant((1, 1, 1)), camera_medium=0)
    mean, var = render(backend, scene, (8, 8), 128)
    within_noise(mean, var, np.exp(-4 * sigma_t))


def test_only_scenes_with_media_compile_the_volumetric_paths():
    plain = compile_scene(load_scene("cornell-box"))
    assert not plain.features(plain.scene.settings, plain.scene.camera).media
    assert "MEDIA" not in plain.features(plain.scene.settings, plain.scene.camera).defines()
    foggy = compile_scene(medium_scene("null", Medium.checked("fog", 0.1, 0.5)))
    assert "MEDIA" in foggy.features(foggy.scene.settings, foggy.scene.camera).defines()


# -- the media's parameters --

@pytest.mark.parametrize("call,field", [
    (lambda: Medium.checked("m", -0.1, 1.0), "sigma_a"),
    (lambda: Medium.checked("m", 0.1, [1.0, float("nan"), 1.0]), "sigma_s"),
    (lambda: Medium.checked("m", 0.1, 1.0, g=1.0), "g"),
    (lambda: Medium.checked("m", 0.1, 1.0, g=-1.5), "g"),
    (lambda: Medium.checked("m", 1e30, 1.0), "sigma_a"),
    (lambda: Medium.from_albedo("m", 1.0, 1.5), "albedo"),
    (lambda: Medium.from_albedo("m", float("inf"), 0.5), "sigma_t"),
])
def test_bad_coefficients_are_refused_naming_the_field(call, field):
    with pytest.raises(ValueError, match=f"^{field}: "):
        call()


def test_mitsuba_parameters_mean_sigma_s_equals_albedo_times_sigma_t():
    m = Medium.from_albedo("m", [2.0, 1.0, 0.5], [0.5, 1.0, 0.0])
    np.testing.assert_allclose(m.sigma_s, [1.0, 1.0, 0.0])
    np.testing.assert_allclose(m.sigma_t, [2.0, 1.0, 0.5])


# -- the readers --

TOML_SCENE = """
[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
medium = "fog"
[media]
fog = { sigma_a = 0.1, sigma_s = [0.5, 0.6, 0.7], g = 0.3 }
milk = { sigma_t = 2.0, albedo = 0.9, scale = 3 }
[[spheres]]
center = [0, 0, 0]
radius = 1
material = { type = "null" }
interior = "milk"
exterior = "fog"
[[spheres]]
center = [3, 0, 0]
radius = 1
material = { type = "diffuse", rho_d = 0.5 }
"""


def test_toml_media_shapes_and_camera(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text(TOML_SCENE)
    s = load_scene(str(path))
    fog, milk = s.media
    np.testing.assert_allclose(fog.sigma_s, [0.5, 0.6, 0.7])
    np.testing.assert_allclose(fog.sigma_a, 0.1)
    assert fog.g == 0.3
    np.testing.assert_allclose(milk.sigma_t, 6.0)
    np.testing.assert_allclose(milk.sigma_s, 5.4)
    assert s.camera_medium == 0
    assert s.sphere_media == [MediumInterface(1, 0), None]


@pytest.mark.parametrize("edit,expected", [
    (('sigma_a = 0.1', 'sigma_a = -0.1'), "media.fog.sigma_a: "),
    (('g = 0.3', 'g = 1.0'), "media.fog.g: "),
    (('interior = "milk"', 'interior = "cream"'), "spheres[0].interior: no medium named 'cream'"),
    (('medium = "fog"', 'medium = "smoke"'), "camera.medium: no medium named 'smoke'"),
    (('milk = { sigma_t', 'milk = { sigma_a = 1, sigma_t'), "media.milk: give either"),
    (('albedo = 0.9', 'albedo = 1.2'), "media.milk.albedo: "),
    (('{ type = "null" }', '{ type = "null", Le = 1 }'), "spheres[0].material.Le: a null material"),
])
def test_bad_toml_media_give_one_line_naming_the_field(tmp_path, edit, expected):
    path = tmp_path / "m.toml"
    assert edit[0] in TOML_SCENE
    path.write_text(TOML_SCENE.replace(*edit))
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    assert expected in str(e.value) and "\n" not in str(e.value)


def test_converted_media_read_back_the_same(tmp_path):
    from pathtrace.scene.toml_writer import scene_toml
    path = tmp_path / "m.toml"
    path.write_text(TOML_SCENE)
    s = load_scene(str(path))
    out = tmp_path / "out.toml"
    out.write_text(scene_toml(s, out))
    back = load_scene(str(out))
    for a, b in zip(s.media, back.media):
        np.testing.assert_allclose(a.sigma_a, b.sigma_a, rtol=1e-6)
        np.testing.assert_allclose(a.sigma_s, b.sigma_s, rtol=1e-6)
        assert a.g == pytest.approx(b.g)
    assert back.sphere_media == s.sphere_media and back.camera_medium == s.camera_medium


MITSUBA = """<scene version="3.0.0">
    <medium type="homogeneous" id="smoke">
        <float name="sigma_t" value="0.5"/>
        <float name="scale" value="4"/>
        <rgb name="albedo" value="0.2, 0.5, 0.8"/>
        <phase type="hg"/>
    </medium>
    <sensor type="perspective"><ref id="smoke"/></sensor>
    <shape type="sphere">
        <bsdf type="null"/>
        <ref name="interior" id="smoke"/>
    </shape>
    <shape type="sphere">
        <point name="center" x="3" y="0" z="0"/>
        <medium type="homogeneous" name="exterior"><phase type="isotropic"/></medium>
    </shape>
    <shape type="sphere">
        <point name="center" x="-3" y="0" z="0"/>
    </shape>
</scene>"""


def test_mitsuba_media(tmp_path):
    """Mitsuba 3's homogeneous medium (sigma_t times scale, albedo; defaults 1 and 0.75), its hg
    phase function (g 0.8 by default), a shape's interior and exterior (the other side vacuum),
    the sensor's medium, and the null BSDF."""
    path = tmp_path / "m.xml"
    path.write_text(MITSUBA)
    s = load_scene(str(path))
    smoke, other = s.media
    np.testing.assert_allclose(smoke.sigma_t, 2.0)
    np.testing.assert_allclose(smoke.sigma_s, [0.4, 1.0, 1.6])
    assert smoke.g == pytest.approx(0.8)
    np.testing.assert_allclose(other.sigma_t, 1.0)
    np.testing.assert_allclose(other.sigma_s, 0.75)
    assert other.g == 0.0
    assert s.camera_medium == 0
    assert s.sphere_media == [MediumInterface(0, -1), MediumInterface(-1, 1), None]
    assert s.materials.get(int(s.sphere_material[0])).type == "null"


@pytest.mark.parametrize("edit,expected", [
    (('type="homogeneous" id="smoke"', 'type="heterogeneous" id="smoke"'), "homogeneous media only"),
    (('<float name="scale" value="4"/>', '<float name="scale" value="-4"/>'), "scale: must lie in [0, inf), got -4"),
    (('<rgb name="albedo" value="0.2, 0.5, 0.8"/>', '<float name="albedo" value="2"/>'), "albedo: "),
    (('<phase type="hg"/>', '<phase type="hg"><float name="g" value="1"/></phase>'), "g: "),
    (('<ref name="interior" id="smoke"/>', '<ref name="interior" id="fog"/>'), "no element has id"),
])
def test_bad_mitsuba_media_give_one_line(tmp_path, edit, expected):
    path = tmp_path / "m.xml"
    assert edit[0] in MITSUBA
    path.write_text(MITSUBA.replace(*edit))
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    assert expected in str(e.value) and "\n" not in str(e.value) and "m.xml:" in str(e.value)


PBRT = """LookAt 0 0 5  0 0 0  0 1 0
MediumInterface "" "air"
Camera "perspective" "float fov" 40
WorldBegin
MakeNamedMedium "air" "string type" "homogeneous" "rgb sigma_a" [0.01 0.02 0.03] "rgb sigma_s" [0.1 0.1 0.1]
    "float scale" 2 "float g" -0.3
MakeNamedMedium "ink" "string type" "homogeneous" "spectrum sigma_s" [300 0.5 800 0.5]
AttributeBegin
  MediumInterface "ink" "air"
  Material "interface"
  Shape "sphere" "float radius" 1
AttributeEnd
AttributeBegin
  MediumInterface "air" "air"
  Material "diffuse"
  Translate 3 0 0
  Shape "sphere" "float radius" 1
AttributeEnd
AttributeBegin
  Material "interface"
  Translate -3 0 0
  Shape "sphere" "float radius" 1
  MediumInterface "ink" "ink"
  Shape "sphere" "float radius" 2
AttributeEnd
"""


def test_pbrt_media(tmp_path):
    """pbrt-v4's MakeNamedMedium (sigma_a, sigma_s times scale, g; sigma_a 1 by default), named
    before it is made; MediumInterface's inside and outside (no transition where they are the
    same); the camera in the outside medium current at Camera; interface shapes as null
    surfaces, left out where they bound nothing; the state's media persist past WorldBegin."""
    path = tmp_path / "m.pbrt"
    path.write_text(PBRT)
    s = load_scene(str(path))
    air, ink = s.media
    np.testing.assert_allclose(air.sigma_a, [0.02, 0.04, 0.06])
    np.testing.assert_allclose(air.sigma_s, 0.2)
    assert air.g == pytest.approx(-0.3)
    np.testing.assert_allclose(ink.sigma_a, 1.0)
    np.testing.assert_allclose(ink.sigma_s, 0.5)
    assert s.camera_medium == 0
    assert len(s.spheres) == 3
    assert s.sphere_media == [MediumInterface(1, 0), None, MediumInterface(-1, 0)]
    assert s.materials.get(int(s.sphere_material[0])).type == "null"


@pytest.mark.parametrize("edit,expected", [
    (('MediumInterface "ink" "air"', 'MediumInterface "ink" "vapour"'), "no medium named 'vapour'"),
    (('"float g" -0.3', '"float g" -1.3'), "'g': "),
    (('"rgb sigma_a" [0.01 0.02 0.03]', '"rgb sigma_a" [0.01 -0.02 0.03]'), "'sigma_a': "),
    (('MakeNamedMedium "ink"', 'MakeNamedMedium "air"'), "a second medium named 'air'"),
])
def test_bad_pbrt_media_give_one_line(tmp_path, edit, expected):
    path = tmp_path / "m.pbrt"
    assert edit[0] in PBRT
    path.write_text(PBRT.replace(*edit))
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    assert expected in str(e.value) and "\n" not in str(e.value)


def test_pbrt_grid_media_warn_and_render_as_vacuum(tmp_path, capsys):
    path = tmp_path / "m.pbrt"
    path.write_text(PBRT.replace('"ink" "string type" "homogeneous"', '"ink" "string type" "uniformgrid"'))
    s = load_scene(str(path))
    assert "homogeneous media only" in capsys.readouterr().err
    np.testing.assert_allclose(s.media[1].sigma_t, 0.0)


def test_an_open_glass_mesh_bounding_a_medium_is_warned_of(tmp_path, capsys):
    path = tmp_path / "m.toml"
    path.write_text(TOML_SCENE + """
[[meshes]]
material = { type = "dielectric" }
interior = "milk"
vertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0]]
faces = [[0, 1, 2]]
""")
    load_scene(str(path))
    lines = [line for line in capsys.readouterr().err.splitlines() if "bounds a medium but is not closed" in line]
    assert len(lines) == 1 and f"warning: {path}:" in lines[0], lines     # the file (and line) that gives it
