"""Next-event estimation with MIS: unbiased (it converges to the image of the report's
estimator), and it lowers the variance by the factors measured below."""

from dataclasses import replace

import numpy as np
import pytest

from pathtrace.cameras import PerspectiveCamera
from pathtrace.scene.environment import Environment
from pathtrace.materials import pack
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import Mesh, SceneBuilder, diffuse, load_scene
from tests.scene_files import SCENE_FILES, image_mean
from tests.stats import z_test

SPP = 2048
SIZE = (64, 36)


def box_filtered(env, k=8):
    h, w, _ = env.image.shape
    image = env.image.reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3)).astype(np.float32)
    return replace(env, image=image)


def hdr_scene():
    """The demo without its small near-mirror sphere (n = 3000), under the Venice sunset map
    box-filtered 8x8 (still HDR, its sun 5x dimmer and wider). With the full map, paths that
    the report's estimator finds only by rare chance (floor -> mirror -> sun) leave its sample
    variance at test sample counts too small to test against; test_hdr_lit_sphere_matches_
    quadrature covers the full-strength mapping."""
    s = load_scene("demo")
    keep = np.arange(len(s.spheres)) != 4
    return replace(s, spheres=s.spheres[keep], sphere_material=s.sphere_material[keep],
                   sphere_names=None, environment=box_filtered(s.environment))


def many_lights_scene(n=128):
    """A ceiling of 2 n^2 small emissive triangles (a height field facing down, each triangle
    its own radiance, spread over three decades) above a diffuse floor, in a black world: next-
    event estimation chooses among 32,768 lights."""
    rng = np.random.default_rng(11)
    b = SceneBuilder()
    floor = np.array([[-6, 0, -6], [-6, 0, 6], [6, 0, 6], [6, 0, -6]], np.float32)
    b.add_mesh(Mesh("floor", floor, np.array([[0, 1, 2], [0, 2, 3]], np.int32), None, b.material(diffuse(0.5))))
    x = np.linspace(-3, 3, n + 1)
    gx, gz = np.meshgrid(x, x, indexing="ij")
    gy = 1.6 + 0.15 * np.sin(2.1 * gx) * np.cos(1.7 * gz)
    corners = np.stack([gx, gy, gz], -1).astype(np.float32)
    quads = np.stack([corners[:-1, :-1], corners[:-1, 1:], corners[1:, 1:], corners[1:, :-1]], 2).reshape(-1, 4, 3)
    triangles = np.concatenate([quads[:, [0, 2, 1]], quads[:, [0, 3, 2]]])     # facing down
    radiance = 10.0 ** rng.uniform(-2, 1, (len(triangles), 1)) * rng.uniform(0.3, 1, (len(triangles), 3))
    rows = b.materials.add_rows(pack("black", {}, emission=radiance))
    one = np.array([[0, 1, 2]], np.int32)
    for k, (t, row) in enumerate(zip(triangles, rows)):
        b.add_mesh(Mesh(f"lamp {k}", t, one, None, int(row)))
    return b.build("many-lights", camera=PerspectiveCamera([0, 1.0, 4.5], [0, 0.4, 0], [0, 1, 0], 50.0),
                   environment=Environment.constant((0, 0, 0)))


# the materials showcase: every BSDF type, delta ones (no light sampling there) among them;
# many-lights: the light choice among tens of thousands of emitters
SCENES = {"simple": lambda: load_scene("simple"), "hdr": hdr_scene,
          "materials": lambda: load_scene("materials"), "many-lights": many_lights_scene}
# Per-pixel variance at equal samples per pixel, report's estimator / NEE (the median over
# pixels; measured 2026-11-24 on PoCL: simple 14.0, hdr 2.25, materials 445, many-lights 3.4).
# The test asks for a margin below what was measured, so that a regression shows.
MIN_VARIANCE_RATIO = {"simple": 9.0, "hdr": 1.8, "materials": 150.0, "many-lights": 2.5}


# Samples per pixel: where paths without NEE meet the lights rarely (a small lamp, a sun), enough
# that a block's sample variance has seen them; the many lights' ceiling fills half the view,
# and its 4096-sample pair took 47 s of the suite on two cores
SCENE_SPP = {"many-lights": 1024}


def render(backend, scene, nee, seed, spp):
    r = Renderer(backend, scene.with_settings(nee=nee, seed=seed), *SIZE)
    for _ in range(spp // 256):
        r.add_samples(256)
    r.finish()
    assert r.dropped_samples() == 0     # a NaN dropped would show as a bias, not as what it is
    return r.mean(), r.variance()


@pytest.fixture(scope="module", params=list(SCENES))
def pair(request, backend):
    scene, spp = SCENES[request.param](), SCENE_SPP.get(request.param, SPP)
    return request.param, spp, render(backend, scene, False, 1, spp), render(backend, scene, True, 2, spp)


def test_nee_converges_to_the_same_image(pair):
    _, spp, (m0, v0), (m1, v1) = pair
    ok, p, threshold = z_test(m0, v0 / spp, m1, v1 / spp, block=4)
    assert ok, (p, threshold)


def test_nee_lowers_the_variance(pair):
    name, _, (_, v0), (_, v1) = pair
    ratio = np.median(v0.mean(-1) / np.maximum(v1.mean(-1), 1e-12))
    print(f"{name}: variance ratio {ratio:.2f}")
    assert ratio >= MIN_VARIANCE_RATIO[name], ratio


def bilinear_map(image, factor=4):
    """The map as kernels/environment.cl looks it up (bilinear, wrapping in u, clamped in v),
    sampled at `factor` times its resolution, with the solid angle of each sample."""
    h, w, _ = image.shape
    v = (np.arange(h * factor) + 0.5) / (h * factor)
    u = (np.arange(w * factor) + 0.5) / (w * factor)
    x, y = u * w - 0.5, np.clip(v * h - 0.5, 0, h - 1)
    x0 = np.floor(x).astype(int)
    ax = x - x0
    x0 %= w
    x1 = (x0 + 1) % w
    y0 = np.floor(y).astype(int)
    ay = y - y0
    y1 = np.minimum(y0 + 1, h - 1)
    row = lambda yy: image[yy][:, x0] * (1 - ax)[None, :, None] + image[yy][:, x1] * ax[None, :, None]  # noqa: E731
    radiance = row(y0) * (1 - ay)[:, None, None] + row(y1) * ay[:, None, None]
    theta = np.pi * v
    solid_angle = np.sin(theta)[:, None] * (np.pi / (h * factor)) * (2 * np.pi / (w * factor)) * np.ones_like(u)
    return radiance, theta, u, solid_angle


@pytest.mark.parametrize("nee", [True, False])
def test_hdr_lit_sphere_matches_quadrature(backend, nee):
    """A lone diffuse sphere (albedo a) under an HDR map, direct light only: its radiance at
    normal n is a / pi * integral of L(w) max(0, n . w) dw, summed here over the map."""
    from pathtrace.cameras import PerspectiveCamera
    from pathtrace.scene import RenderSettings, SceneBuilder, diffuse

    env = box_filtered(load_scene("demo").environment)
    env = replace(env, rotation=75.0)
    albedo, w, h = 0.8, 48, 32
    b = SceneBuilder()
    b.add_sphere((0, 0, 0), 1.0, diffuse(albedo))
    camera = PerspectiveCamera([0, 0.5, 4], [0, 0, 0], [0, 1, 0], 35.0)
    scene = b.build("sphere", camera=camera, environment=env,
                    settings=RenderSettings(width=w, height=h, max_depth=2, russian_roulette="off", nee=nee))
    radiance, theta, u, solid_angle = bilinear_map(env.image)
    phi = 2 * np.pi * (u - env.rotation / 360 - 0.5)
    t, f = np.meshgrid(theta, phi, indexing="ij")
    dirs = np.stack([np.sin(t) * np.sin(f), np.cos(t), -np.sin(t) * np.cos(f)], -1).reshape(-1, 3)
    weighted = radiance.reshape(-1, 3) * solid_angle.reshape(-1, 1)
    # the sphere point seen through each pixel's centre; pixels on the outline left out
    fwd, right, up = camera.basis(w / h)
    def ray(sx, sy):
        x = (np.arange(w) + sx) / w * 2 - 1
        y = 1 - (np.arange(h) + sy) / h * 2
        d = fwd + x[None, :, None] * right + y[:, None, None] * up
        return d / np.linalg.norm(d, axis=-1, keepdims=True)
    def hits(d):
        b_ = d @ camera.eye
        return b_ * b_ - (camera.eye @ camera.eye - 1) > 0
    inside = np.all([hits(ray(sx, sy)) for sx in (0, 0.5, 1) for sy in (0, 0.5, 1)], axis=0)
    d = ray(0.5, 0.5)[inside]
    b_ = d @ camera.eye
    normal = camera.eye + (-b_ - np.sqrt(b_ * b_ - (camera.eye @ camera.eye - 1)))[:, None] * d
    expected = albedo / np.pi * (np.maximum(normal @ dirs.T, 0) @ weighted)

    r = Renderer(backend, scene)
    for _ in range(8):
        r.add_samples(128)
    r.finish()
    got, var = r.mean()[inside], r.variance()[inside] / r.samples
    ok, p, threshold = z_test(got[:, None], var[:, None], expected[:, None])
    assert ok, (p, threshold)
    assert abs(np.mean(got / expected) - 1) < 0.005


def test_a_phong_lobe_of_exponent_1e8_stays_finite_and_unbiased(backend, tmp_path):
    """n = 1e8 lies in the documented range (n >= 0). A rounded cos(alpha) just above 1 raised to
    the 1e8th overflowed, and the power heuristic's squared densities gave inf / inf: NaN pixels
    with NEE (#12). Both estimators must give finite pixels and the same mean."""
    path = tmp_path / "sharp.toml"
    path.write_text('[camera]\neye = [0, 1, 5]\nlook_at = [0, 0, 0]\n[environment]\ncolor = 0.5\n'
                    '[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\n'
                    'material = { type = "phong", rho_d = 0.2, rho_s = 0.7, n = 1e8 }\n'
                    '[[spheres]]\ncenter = [2, 2, 0]\nradius = 0.3\nmaterial = { type = "emitter", Le = 20 }\n')
    scene = load_scene(str(path))
    means, errors = [], []
    for nee in (True, False):
        r = Renderer(backend, scene.with_settings(nee=nee), 32, 24)
        r.add_samples(64)
        image = r.mean()
        assert np.all(np.isfinite(image))
        means.append(image.mean())
        # the image mean's standard error, from the pixels' sample variances
        errors.append(np.sqrt(r.variance().sum() / 64) / image.size)
    assert abs(means[0] - means[1]) < 5 * np.hypot(*errors)


# -- The NEE invariant on every scene the tests hold --
# Next-event estimation with MIS, its light chosen by power or through the light tree, converges
# to the image of paths alone, which meet the emitters and the environment by chance. Compared
# here by the whole image's mean, within five standard errors: per pixel, where paths alone meet
# a small light rarely, a few hundred samples leave the sample variance blind to it (the block
# test above takes thousands). It is the cheapest detector of emitter and MIS bugs, a light whose
# sampled density or side disagrees with what a path that hits it sees: the two-sided pbrt
# lights of review 2026-11-28 (F1) disagreed by 19 %, and on area_twosided_lit_floor this test
# measured 5.8 and 6.5 standard errors before the fix, 0.3 and 0.2 after. Delta lights, which
# no path can hit, are taken out of the scenes.

SCENE_SPP_BY_NEE = {False: 512, True: 128}


def test_every_kind_of_test_scene_is_here():
    assert {p.suffix for p in SCENE_FILES} == {".xml", ".pbrt", ".toml"} and len(SCENE_FILES) > 50


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_nee_by_power_and_by_the_light_tree_converges_to_the_image_of_paths_alone(backend, monkeypatch, path):
    monkeypatch.setenv("PATHTRACE_PROGRAM", "generic")      # one program for every scene
    scene = replace(load_scene(str(path)), lights=[]).with_settings(russian_roulette="off", seed=3)
    plain, plain_error = image_mean(backend, scene.with_settings(nee=False), SCENE_SPP_BY_NEE[False])
    for sampler in ("power", "tree"):
        mean, error = image_mean(backend, scene.with_settings(nee=True, light_sampler=sampler, seed=4), SCENE_SPP_BY_NEE[True])
        assert np.all(np.abs(mean - plain) <= 5 * np.hypot(error, plain_error) + 1e-6 * plain), (sampler, mean, plain)
