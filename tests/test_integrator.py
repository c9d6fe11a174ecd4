"""The path tracer against closed-form answers: furnaces, the irradiance of a sphere light, and
a bare view of the environment map."""

from dataclasses import replace

import numpy as np
import pytest

from pathtrace.cameras import PerspectiveCamera
from pathtrace.scene.environment import Environment
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import RenderSettings, SceneBuilder, diffuse, emitter
from tests.stats import z_test


def render(backend, scene, spp):
    r = Renderer(backend, scene)
    for _ in range(spp // 8):
        r.add_samples(8)
    r.finish()
    return r.mean(), r.variance() / r.samples, r


def furnace_scene(albedo, env=1.0, material=None, **settings):
    """A unit sphere (diffuse of `albedo`, or `material`) under a uniform environment."""
    b = SceneBuilder()
    b.add_sphere((0, 0, 0), 1.0, material if material is not None else diffuse(albedo))
    return b.build("furnace", camera=PerspectiveCamera([0, 0, 4], [0, 0, 0], [0, 1, 0], 40.0),
                   environment=Environment.constant((env, env, env)),
                   settings=RenderSettings(width=48, height=32, **settings))


@pytest.mark.parametrize("settings", [dict(nee=False), dict(nee=False, russian_roulette="albedo"),
                                      dict(max_depth=8, russian_roulette="off", nee=False),
                                      dict(nee=True)])
def test_white_furnace_renders_one_everywhere(backend, settings):
    """A diffuse sphere of albedo 1 under a uniform environment of radiance 1: every path
    carries exactly 1 (the weight rho_d / P_d is 1 and paths end when they escape; with NEE the
    light sample and the escaping bounce have equal densities, so each carries half)."""
    mean, var, _ = render(backend, furnace_scene(1.0, **settings), 32)
    np.testing.assert_allclose(mean, 1.0, atol=1e-5)
    assert var.max() < 1e-8       # float32 rounding of the frame changes, not noise


def test_white_furnace_whose_light_and_bsdf_densities_differ(backend):
    """The constant-environment furnace above cannot see an MIS error: there both strategies
    sample the cosine, so every weight is 1/2. Here the environment is a map of constant
    texels, which next-event estimation samples by the map's distribution (uniform over the
    sphere) while the diffuse BSDF samples the cosine: the MIS weights differ from sample to
    sample, and only weights that sum to one per direction keep every pixel at 1."""
    scene = furnace_scene(1.0, nee=True)
    scene.environment = Environment(image=np.ones((16, 32, 3), np.float32), source="constant map")
    mean, var, _ = render(backend, scene, 512)
    assert var.max() > 1e-4                      # the weights do vary
    ok, p, threshold = z_test(mean, var, np.ones_like(mean), block=4)
    assert ok, (p, threshold)
    np.testing.assert_allclose(mean.mean(), 1.0, atol=2e-3)


@pytest.mark.parametrize("nee", [False, True])
@pytest.mark.parametrize("rr", [True, False])
def test_grey_furnace_renders_albedo_times_environment(backend, rr, nee):
    """A convex sphere's reflected rays always escape, so L = albedo * L_env on the sphere and
    L_env around it; with Russian roulette only in expectation."""
    albedo, env = np.array([0.2, 0.5, 0.8]), 2.0
    scene = furnace_scene(albedo, env, nee=nee, **({} if rr else dict(max_depth=8, russian_roulette="off")))
    mean, var, r = render(backend, scene, 256)
    # which pixels see the sphere, from the pixel's corners (pixels on the outline are mixed)
    on = sphere_coverage(r, scene)
    expected = np.where(on[..., None] == 1, albedo * env, env)
    inside = (on == 0) | (on == 1)
    if rr:
        ok, p, threshold = z_test(mean[inside][:, None], var[inside][:, None], expected[inside][:, None])
        assert ok, (p, threshold)
    else:
        np.testing.assert_allclose(mean[inside], expected[inside], rtol=1e-5)


def sphere_coverage(renderer, scene):
    """Fraction of each pixel's 3x3 sub-samples (corners, edge midpoints, centre) whose primary
    ray hits sphere 0. The outline is convex, so 1 means the whole pixel sees the sphere."""
    w, h = renderer.width, renderer.height
    fwd, right, up = scene.camera.basis(w / h)
    s = scene.spheres[0].astype(np.float64)
    hits = np.zeros((h, w))
    for sy in (0.0, 0.5, 1.0):
        for sx in (0.0, 0.5, 1.0):
            x = (np.arange(w) + sx) / w * 2 - 1
            y = 1 - (np.arange(h) + sy) / h * 2
            d = fwd + x[None, :, None] * right + y[:, None, None] * up
            d /= np.linalg.norm(d, axis=-1, keepdims=True)
            f = scene.camera.eye - s[:3]
            b = np.sum(d * f, -1)
            hits += (b * b - (f @ f - s[3] ** 2) > 0) & (b < 0)
    return hits / 9


@pytest.mark.parametrize("nee", [False, True])
def test_sphere_light_irradiance(backend, nee):
    """A diffuse floor under a sphere light in a black world, direct light only (max_depth 2).
    A uniform sphere light of radiance Le and radius r, fully above the horizon, gives
    irradiance E = pi Le r^2 cos(theta) / d^2 (as a point source of the same power), so the
    floor's radiance is rho Le r^2 cos(theta) / d^2."""
    rho, le, r_light, centre = 0.7, 50.0, 0.5, np.array([0.0, 2.0, 0.0])
    b = SceneBuilder()
    b.add_sphere((0, -1e4, 0), 1e4, diffuse(rho))     # a floor, flat to 1e-4 over the view
    b.add_sphere(centre, r_light, emitter(le))
    scene = b.build("irradiance", camera=PerspectiveCamera([0, 6, 6], [0, 0, 0], [0, 1, 0], 50.0),
                    environment=Environment.constant((0, 0, 0)),
                    settings=RenderSettings(width=40, height=30, max_depth=2, russian_roulette="off", nee=nee))
    mean, var, r = render(backend, scene, 1024)
    # the closed form averaged over each pixel (8x8 points), as the jittered samples average it
    w, h = r.width, r.height
    fwd, right, up = scene.camera.basis(w / h)
    floor_c, floor_r = scene.spheres[0, :3].astype(np.float64), 1e4

    def closed_form(sx, sy):
        x = (np.arange(w) + sx) / w * 2 - 1
        y = 1 - (np.arange(h) + sy) / h * 2
        d = fwd + x[None, :, None] * right + y[:, None, None] * up
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        f = scene.camera.eye - floor_c
        bq = np.sum(d * f, -1)
        disc = bq * bq - (f @ f - floor_r ** 2)
        t = np.where(disc > 0, -bq - np.sqrt(np.maximum(disc, 0)), -1)
        p = scene.camera.eye + t[..., None] * d
        to_light = centre - p
        dist = np.linalg.norm(to_light, axis=-1)
        return rho * le * r_light ** 2 * np.sum((p - floor_c) / floor_r * to_light, -1) / dist ** 3, t

    offsets = (np.arange(8) + 0.5) / 8
    expected = np.mean([closed_form(sx, sy)[0] for sx in offsets for sy in offsets], axis=0)
    t = closed_form(0.5, 0.5)[1]
    # leave out the pixels that see the light itself or lie next to it
    light_px = sphere_coverage(r, replace(scene, spheres=scene.spheres[1:]))
    floor = (t > 0) & (np.abs(np.gradient(light_px)[0]) + np.abs(np.gradient(light_px)[1]) + light_px == 0)
    assert floor.sum() > 0.8 * w * h
    # Without NEE each sample is rho Le (the bounce met the light) or 0: a binomial with the
    # exact variance below, which stays right where only a few of a pixel's samples meet the
    # light. With NEE every sample sees the light and the sample variance is reliable. Outside
    # `floor` the comparison is switched off by putting the expectation there.
    spp = r.samples
    var_of_mean = var[..., 0] if nee else expected * (rho * le - expected) / spp
    var_of_mean = np.where(floor, var_of_mean, 0.0)
    got = np.where(floor, mean[..., 0], expected)
    ok, pmin, threshold = z_test(got[..., None], var_of_mean[..., None], expected[..., None], block=4)
    assert ok, (pmin, threshold)


def test_bare_environment_reproduces_the_map(backend):
    """Looking at the sky alone (max_depth 1), each pixel shows the map at its direction, through
    the documented lat-long mapping, with rotation and intensity applied."""
    hmap, wmap = 32, 64
    v, u = np.meshgrid((np.arange(hmap) + 0.5) / hmap, (np.arange(wmap) + 0.5) / wmap, indexing="ij")
    smooth = lambda u, v: np.stack([1 + 0.5 * np.sin(2 * np.pi * u), 1 + 0.5 * np.cos(np.pi * v), 1 + 0 * u], -1)  # noqa: E731
    env = Environment(smooth(u, v).astype(np.float32), intensity=2.0, rotation=90.0)
    b = SceneBuilder()
    b.add_sphere((0, 0, 50), 0.1, diffuse(0.5))       # behind the camera, out of view
    scene = b.build("sky", camera=PerspectiveCamera([0, 0, 0], [0, 0.3, -1], [0, 1, 0], 60.0), environment=env,
                    settings=RenderSettings(width=32, height=24, max_depth=1, russian_roulette="off"))
    mean, _, r = render(backend, scene, 64)
    fwd, right, up = scene.camera.basis(32 / 24)
    x = (np.arange(32) + 0.5) / 32 * 2 - 1
    y = 1 - (np.arange(24) + 0.5) / 24 * 2
    d = fwd + x[None, :, None] * right + y[:, None, None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    uu = (0.5 + np.arctan2(d[..., 0], -d[..., 2]) / (2 * np.pi) + 0.25) % 1.0
    vv = np.arccos(d[..., 1]) / np.pi
    expected = 2.0 * smooth(uu, vv)
    # bilinear lookup of a smooth map and jitter within the pixel: within a percent
    np.testing.assert_allclose(mean, expected, rtol=0.015)


def lambert_irradiance(p, corners, le):
    """Irradiance at points p (normal +y) from a polygon of radiance le, by Lambert's formula:
    E = le / 2 * sum over edges of theta_i (Gamma_i . n), theta_i the angle the edge subtends
    and Gamma_i the unit normal of the plane through p and the edge."""
    total = np.zeros(p.shape[:-1])
    for i in range(len(corners)):
        a, b = corners[i] - p, corners[(i + 1) % len(corners)] - p
        cross = np.cross(a, b)
        theta = np.arctan2(np.linalg.norm(cross, axis=-1), np.sum(a * b, -1))
        total += theta * cross[..., 1] / np.linalg.norm(cross, axis=-1)
    return le / 2 * np.abs(total)


@pytest.mark.parametrize("nee", [False, True])
def test_square_light_irradiance_matches_lambert(backend, nee):
    """A diffuse floor (a quad) under a square emitter (a quad facing down) in a black world,
    direct light only: the floor's radiance is rho / pi times Lambert's irradiance."""
    from pathtrace.scene import Mesh
    rho, le, h = 0.6, 5.0, 1.0
    light = np.array([[-0.5, h, -0.5], [0.5, h, -0.5], [0.5, h, 0.5], [-0.5, h, 0.5]])
    b = SceneBuilder()
    floor = np.array([[-20, 0, -20], [-20, 0, 20], [20, 0, 20], [20, 0, -20]], np.float32)
    quad = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    b.add_mesh(Mesh("floor", floor, quad, None, b.material(diffuse(rho))))
    b.add_mesh(Mesh("light", light.astype(np.float32), quad, None, b.material(emitter(le))))
    scene = b.build("lambert", camera=PerspectiveCamera([0, 2.5, 2.5], [0, 0, 0], [0, 1, 0], 55.0),
                    environment=Environment.constant((0, 0, 0)),
                    settings=RenderSettings(width=40, height=30, max_depth=2, russian_roulette="off", nee=nee))
    # the light faces down, so its (black) back is what the camera sees of it
    assert np.dot(np.cross(light[1] - light[0], light[2] - light[0]), [0, 1, 0]) < 0
    mean, var, r = render(backend, scene, 1024)
    w, hgt = r.width, r.height
    fwd, right, up = scene.camera.basis(w / hgt)

    def floor_point(sx, sy):
        x = (np.arange(w) + sx) / w * 2 - 1
        y = 1 - (np.arange(hgt) + sy) / hgt * 2
        d = fwd + x[None, :, None] * right + y[:, None, None] * up
        t_floor = -scene.camera.eye[1] / d[..., 1]
        t_light = (h - scene.camera.eye[1]) / d[..., 1]
        q = scene.camera.eye + t_light[..., None] * d
        blocked = (t_light > 0) & (np.abs(q[..., 0]) <= 0.5) & (np.abs(q[..., 2]) <= 0.5)
        p = scene.camera.eye + t_floor[..., None] * d
        on_floor = (t_floor > 0) & (np.abs(p[..., 0]) < 20) & (np.abs(p[..., 2]) < 20)
        return p, on_floor & ~blocked

    offsets = (np.arange(8) + 0.5) / 8
    samples = [floor_point(sx, sy) for sx in offsets for sy in offsets]
    expected = np.mean([rho / np.pi * lambert_irradiance(p, light, le) for p, _ in samples], axis=0)
    floor_px = np.all([ok for _, ok in samples], axis=0)
    spp = r.samples
    # without NEE a sample is rho Le (its bounce met the light) or 0: keep the pixels expected
    # to meet it often enough (30 times) for the normal approximation of the test
    floor_px &= expected / (rho * le) * spp > 30
    assert floor_px.sum() > 0.3 * w * hgt
    var_of_mean = var[..., 0] if nee else expected * (rho * le - expected) / spp
    var_of_mean = np.where(floor_px, var_of_mean, 0.0)
    got = np.where(floor_px, mean[..., 0], expected)
    ok, pmin, threshold = z_test(got[..., None], var_of_mean[..., None], expected[..., None], block=3)
    assert ok, (pmin, threshold)


@pytest.mark.parametrize("nee", [False, True])
def test_closed_mesh_white_furnace_renders_one(backend, nee):
    """A subdivided icosahedron of albedo 1 under a uniform environment of radiance 1: every
    pixel converges to 1. (Flat shading: interpolated normals lose the directions that fall
    below the geometric surface, as in Mitsuba 3, so they are not exactly lossless.)"""
    from pathtrace.scene import Mesh
    from tests.geometry import icosphere
    v, f = icosphere(2)
    b = SceneBuilder()
    b.add_mesh(Mesh("ball", v.astype(np.float32), f.astype(np.int32), None, b.material(diffuse(1.0))))
    scene = b.build("furnace", camera=PerspectiveCamera([0, 0, 4], [0, 0, 0], [0, 1, 0], 40.0),
                    environment=Environment.constant((1, 1, 1)),
                    settings=RenderSettings(width=32, height=24, nee=nee))
    mean, var, _ = render(backend, scene, 64)
    np.testing.assert_allclose(mean, 1.0, atol=2e-3)


@pytest.mark.parametrize("nee", [False, True])
def test_no_light_leaks_into_a_closed_box(backend, nee):
    """A camera inside a closed cube (12 triangles, shared corners, facing in), under a bright
    sky: no path may reach the sky, so the image is exactly black, corners included."""
    from pathtrace.scene import Mesh
    from tests.geometry import cube
    v, f = cube(1.0, inward=True)
    b = SceneBuilder()
    b.add_mesh(Mesh("box", v.astype(np.float32), f.astype(np.int32), None, b.material(diffuse(0.9))))
    scene = b.build("box", camera=PerspectiveCamera([0.3, -0.2, 0.5], [-1, 1, -1], [0, 1, 0], 90.0),
                    environment=Environment.constant((100, 100, 100)),
                    settings=RenderSettings(width=48, height=48, nee=nee, max_depth=16, russian_roulette="off"))
    mean, _, _ = render(backend, scene, 64)
    assert np.all(mean == 0.0)


def textured_emitter_scene(max_depth, nee):
    """A wall that emits a checkerboard of radiance 0.2 and 1.0 (its squares a whole number
    across the view, so 0.6 on average), filling the view, under a black sky."""
    from pathtrace.api import load_dict
    return load_dict({
        "camera": {"eye": [0, 0, 3], "look_at": [0, 0, 0], "vfov": 30},
        "environment": {"color": 0.0},
        "render": {"width": 32, "height": 32, "max_depth": max_depth, "nee": nee},
        "textures": {"board": {"type": "checkerboard", "color0": 0.2, "color1": 1.0, "uv_scale": 4}},
        "materials": {"wall": {"type": "emitter", "Le": "board"}},
        "meshes": [{"material": "wall", "vertices": [[-w, -w, 0], [w, -w, 0], [w, w, 0], [-w, w, 0]],
                    "faces": [[0, 1, 2, 3]], "uvs": [[0, 0], [1, 0], [1, 1], [0, 1]]}
                   for w in [3 * np.tan(np.radians(15))]]})


@pytest.mark.parametrize("nee", [False, True], ids=["no-nee", "nee"])
def test_a_paths_last_vertex_emits_its_textured_radiance(backend, nee):
    """At a path's last vertex the material is not shaded, only its emission looked up
    (kernels/integrator.cl): with max depth 1 the camera rays' vertices are the last, and each
    pixel must get what a longer path gets there (the wall's BSDF is black, so nothing more),
    sample for sample, and the texture, not its mean."""
    images = []
    for depth in (1, 3):
        r = Renderer(backend, textured_emitter_scene(depth, nee))
        r.add_samples(16)
        images.append(r.mean())
    np.testing.assert_array_equal(images[0], images[1])
    assert abs(float(images[0].mean()) - 0.6) < 0.02
    assert np.quantile(images[0], 0.1) < 0.3 and np.quantile(images[0], 0.9) > 0.9
