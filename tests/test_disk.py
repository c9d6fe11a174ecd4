"""The analytic disk (kernels/shapes/disk.cl, app/shapes/disk.py): its area, points, normals, uv
and dp/du against pbrt-v4's formulas (section 6.4) and Mitsuba 3's, the pbrt-v4 and Mitsuba 3
readers' disks (a pbrt disk's texture coordinates (u, 1 - v), and its image as a pbrt mesh of its
uv), and its image against the 256-triangle fan that stood for it before. The registry's tests
(tests/test_shapes.py) cover its BVH hits, sampling and lighting."""

import math

import numpy as np
import pytest

from pathtrace.cameras import PerspectiveCamera
from pathtrace.scene.environment import Environment
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import Mesh, SceneBuilder, diffuse, load_scene
from pathtrace.scene import transform
from pathtrace.shapes import SHAPES, Shape
from tests.stats import z_test
from tests.analytic_shapes import hits_as_pbrt, moved, pbrt_emitter, pbrt_scene
from tests.test_shapes import one_shape_scene, shape_hits

RADIUS, INNER, HEIGHT, PHI_MAX = 1.5, 0.6, 0.25, math.radians(250)


def test_area_is_the_annulus_sector():
    assert SHAPES["disk"].area((RADIUS, INNER, HEIGHT, PHI_MAX)) == pytest.approx(
        math.pi * (RADIUS ** 2 - INNER ** 2) * PHI_MAX / (2 * math.pi))


@pytest.mark.parametrize("flip", [False, True])
@pytest.mark.parametrize("uniform", [True, False])
def test_hits_follow_pbrts_formulas(kernels, flip, uniform):
    """Rays aimed at object points (r cos phi, r sin phi, height) meet the disk there, with
    pbrt-v4's u = phi / phi_max, v = (radius - r) / (radius - inner radius), its dp/du =
    phi_max (-y, x, 0) moved to the world, and the normal +z moved as a normal (turned by
    `flip`); rays at points outside the annulus or beyond phi_max miss."""
    rng = np.random.default_rng(1)
    m = transform.translation([0.3, -0.2, 1.0]) @ transform.rotation([1, 1, 0], 35) \
        @ transform.scaling([1.2] * 3 if uniform else [0.7, 1.6, 1.1])
    scene = one_shape_scene(Shape("d", "disk", (RADIUS, INNER, HEIGHT, PHI_MAX), m, 0, flip=flip))
    n = 2000
    r = np.clip(np.sqrt(rng.uniform(INNER ** 2, RADIUS ** 2, n)), INNER * 1.001, RADIUS * 0.999)
    phi = rng.uniform(0.001, 0.999, n) * PHI_MAX
    local = np.column_stack([r * np.cos(phi), r * np.sin(phi), np.full(n, HEIGHT)])
    side = np.where(rng.random(n) < 0.5, 1.0, -1.0)[:, None]
    above = local + side * rng.uniform(0.5, 3, (n, 1)) * np.array([0.3, -0.2, 1.0])
    h = hits_as_pbrt(kernels, scene, m, above, local, np.column_stack([phi / PHI_MAX, (RADIUS - r) / (RADIUS - INNER)]),
                     PHI_MAX, 2e-5, 2e-4)
    normal = np.linalg.inv(m[:3, :3]).T @ [0, 0, 1]
    normal = (-1 if flip else 1) * normal / np.linalg.norm(normal)
    np.testing.assert_allclose(h["n"], np.broadcast_to(normal, (n, 3)), atol=1e-5)
    # outside the annulus, inside the hole, and in the missing sector
    r_out = np.concatenate([rng.uniform(1.01, 1.5, n // 3) * RADIUS, rng.uniform(0, 0.99, n // 3) * INNER,
                            rng.uniform(INNER, RADIUS, n - 2 * (n // 3))])
    phi_out = np.concatenate([phi[:2 * (n // 3)], rng.uniform(PHI_MAX + 0.01, 2 * math.pi - 0.01, n - 2 * (n // 3))])
    miss = np.column_stack([r_out * np.cos(phi_out), r_out * np.sin(phi_out), np.full(n, HEIGHT)])
    assert np.all(np.isnan(shape_hits(kernels, scene, moved(m, miss + [0, 0, 1]), moved(m, miss))["p"][:, 0]))


def test_mitsuba_disk_has_mitsubas_uv(kernels, tmp_path):
    """Mitsuba 3's disk (src/shapes/disk.cpp) is the unit disk of its to_world, facing its +z,
    with uv (r, phi / 2 pi); flip_normals turns the normal."""
    path = tmp_path / "d.xml"
    path.write_text('<scene version="3.0.0"><shape type="disk"><transform name="to_world"><scale value="2"/>'
                    '<translate value="0, 1, 0"/></transform><boolean name="flip_normals" value="true"/></shape>'
                    '</scene>')
    scene = load_scene(str(path))
    assert not scene.meshes and [s.kind for s in scene.shapes] == ["disk"]
    rng = np.random.default_rng(2)
    r, phi = np.sqrt(rng.random(500)) * 0.999, rng.uniform(0.001, 0.999, 500) * 2 * math.pi
    target = np.column_stack([2 * r * np.cos(phi), 1 + 2 * r * np.sin(phi), np.zeros(500)])
    h = shape_hits(kernels, scene, target + [0, 0, 3], target)
    np.testing.assert_allclose(h["uv"], np.column_stack([r, phi / (2 * math.pi)]), atol=2e-5)
    np.testing.assert_allclose(h["n"], np.broadcast_to([0, 0, -1], (500, 3)), atol=1e-6)


@pytest.mark.parametrize("transform_line, flipped", [("", False), ("ReverseOrientation", True),
                                                      ("Scale 1 1 -1", True), ("ReverseOrientation Scale -1 1 1", False)])
def test_pbrt_disk_is_analytic_with_pbrts_front_and_power(tmp_path, capfd, transform_line, flipped):
    """pbrt-v4's disk keeps its inner radius, phimax and height (no triangles, no warning); its
    front is turned by ReverseOrientation and by a transform that swaps handedness; `power` is
    spread over its area, pi (r^2 - ri^2) phimax / 2 pi (DiffuseAreaLight::Create's
    L power / (pi area))."""
    disk, emission = pbrt_emitter(tmp_path, capfd, f'Translate 0 1 0\n{transform_line}\nShape "disk" "float radius" 2 '
                                  '"float innerradius" 0.5 "float phimax" 270 "float height" 0.1')
    assert disk.kind == "disk" and disk.flip == flipped
    assert disk.params == pytest.approx((2.0, 0.5, 0.1, math.radians(270)))
    area = math.pi * (4 - 0.25) * 0.75
    np.testing.assert_allclose(emission, 10 / (math.pi * area), rtol=1e-5)


def test_a_pbrt_disk_is_textured_at_pbrts_image_coordinates(kernels, tmp_path):
    """pbrt-v4 looks images up at (u, 1 - v) (src/pbrt/textures.cpp, SpectrumImageTexture::
    Evaluate) of its disk's u = phi / phimax, v = (radius - r) / (radius - innerradius)
    (src/pbrt/shapes.h, Disk::InteractionFromIntersection), and pathtrace at (u, v): a pbrt
    disk's hit must carry (u, 1 - v), its tangents along them pbrt's dp/du = phimax (-y, x, 0)
    and -dp/dv = (radius - innerradius) (cos phi, sin phi, 0), its front still +z."""
    scene = pbrt_scene(tmp_path, 'Translate 0.3 0 0\n'
                              'Shape "disk" "float radius" 1.5 "float innerradius" 0.6 "float height" 0.25 "float phimax" 250')
    rng, n = np.random.default_rng(8), 500
    phi = rng.uniform(0.01, math.radians(250) - 0.01, n)
    r = rng.uniform(0.61, 1.49, n)
    local = np.column_stack([r * np.cos(phi), r * np.sin(phi), np.full(n, 0.25)])
    h = shape_hits(kernels, scene, local + [0.3, 0, 2], local + [0.3, 0, 0])
    np.testing.assert_allclose(h["p"], local + [0.3, 0, 0], atol=2e-5)
    np.testing.assert_allclose(h["uv"], np.column_stack([phi / math.radians(250), 1 - (1.5 - r) / 0.9]), atol=2e-5)
    np.testing.assert_allclose(h["dpdu"], math.radians(250) * np.column_stack([-local[:, 1], local[:, 0], np.zeros(n)]),
                               atol=1e-4)
    np.testing.assert_allclose(h["dpdv"], 0.9 * np.column_stack([np.cos(phi), np.sin(phi), np.zeros(n)]), atol=1e-5)
    np.testing.assert_allclose(h["n"], np.broadcast_to([0, 0, 1], (n, 3)), atol=1e-6)


def annulus_mesh(radius, inner, segments=256, rings=8):
    """(P, uv, indices) text of a pbrt-v4 trianglemesh over the annulus of `radius` and `inner`
    at z = 0, its uv at each corner pbrt-v4's Disk's (phi / 2 pi, (radius - r) / (radius - inner)),
    its faces facing +z as the disk does."""
    phi, r = np.meshgrid(np.arange(segments + 1) / segments * 2 * math.pi, np.linspace(radius, inner, rings + 1))
    points = np.stack([r * np.cos(phi), r * np.sin(phi), np.zeros_like(r)], -1)
    uv = np.stack([phi / (2 * math.pi), (radius - r) / (radius - inner)], -1)
    corner = np.arange(rings)[:, None] * (segments + 1) + np.arange(segments)     # ring i from the rim, angle j
    step = segments + 1                                                           # to the next ring in
    faces = np.stack([corner, corner + 1, corner + step + 1, corner, corner + step + 1, corner + step], -1)
    return tuple(" ".join(f"{x:.9g}" for x in np.ravel(a)) for a in (points, uv, faces))


def test_a_pbrt_disk_renders_as_a_pbrt_mesh_of_its_uv(backend, tmp_path):
    """An image whose rows run from red to blue, on a pbrt disk and on a pbrt trianglemesh over
    the same annulus whose corners carry the disk's uv: pbrt-v4 looks both up at (u, 1 - v) of
    their uv (ImageTexture), and so renders them alike; pathtrace's images of the two, lit by a
    uniform sky, agree within noise (a per-pixel Z-test), where the disk's v read unturned puts
    the blue rows at the rim."""
    from PIL import Image
    rows = np.linspace(0, 255, 8).astype(np.uint8)
    Image.fromarray(np.stack([rows[::-1], np.full(8, 40, np.uint8), rows], -1)[:, None].repeat(2, 1)).save(
        tmp_path / "rows.png")
    head = ('LookAt 0 0 3  0 0 0  0 1 0\nCamera "perspective" "float fov" 45\nWorldBegin\n'
            'LightSource "infinite" "rgb L" [1 1 1]\n'
            'Texture "t" "spectrum" "imagemap" "string filename" "rows.png"\nMaterial "diffuse" "texture reflectance" "t"\n')
    points, uv, faces = annulus_mesh(1.0, 0.3)
    images = []
    for seed, shape in enumerate(('Shape "disk" "float radius" 1 "float innerradius" 0.3',
                                  f'Shape "trianglemesh" "point3 P" [{points}] "point2 uv" [{uv}] "integer indices" [{faces}]')):
        path = tmp_path / f"s{seed}.pbrt"
        path.write_text(head + shape + "\n")
        scene = load_scene(str(path))
        assert bool(scene.shapes) == (seed == 0)
        images.append(mean_and_variance(backend, scene.with_settings(max_depth=2, seed=seed), (32, 32), 64))
    (m0, v0), (m1, v1) = images
    ok, p, threshold = z_test(m0, v0, m1, v1, block=2)
    assert ok, (p, threshold)


def mean_and_variance(backend, scene, size, spp):
    """The mean of four launches of `spp` samples per pixel and its per-pixel variance."""
    r = Renderer(backend, scene, *size)
    for _ in range(4):
        r.add_samples(spp)
    r.finish()
    return r.mean(), r.variance() / r.samples


def fan(segments=256):
    """The unit disk as the fan of `segments` triangles that pathtrace drew for a disk before."""
    a = np.arange(segments + 1) / segments * 2 * math.pi
    vertices = np.concatenate([[[0, 0, 0]], np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)])])
    faces = np.column_stack([np.zeros(segments), np.arange(1, segments + 1), np.arange(2, segments + 2)])
    return vertices.astype(np.float32), faces.astype(np.int32)


def test_the_analytic_disk_renders_as_the_old_triangle_fan(backend):
    """A lit disk seen at a slant, analytic against the 256-triangle fan: the same image within
    noise (a per-pixel Z-test); the fan's area is 0.01 % short at the rim, below the noise."""
    m = transform.translation([0, 0.2, 0]) @ transform.rotation([1, 0, 0], -60) @ transform.scaling([1.2] * 3)
    images = []
    for analytic in (True, False):
        b = SceneBuilder()
        row = b.material(diffuse(0.7))
        if analytic:
            b.add_shape(Shape("disk", "disk", (1.0, 0.0, 0.0, 2 * math.pi), m, row))
        else:
            v, f = fan()
            b.add_mesh(Mesh("fan", (v @ m[:3, :3].T + m[:3, 3]).astype(np.float32), f, None, row))
        floor = np.array([[-4, -0.5, -4], [-4, -0.5, 4], [4, -0.5, 4], [4, -0.5, -4]], np.float32)
        b.add_mesh(Mesh("floor", floor, np.array([[0, 1, 2], [0, 2, 3]], np.int32), None, b.material(diffuse(0.5))))
        scene = b.build("disk", camera=PerspectiveCamera([0, 1.5, 4], [0, 0, 0], [0, 1, 0], 40.0),
                        environment=Environment.constant((1.0, 0.9, 0.8)))
        images.append(mean_and_variance(backend, scene.with_settings(max_depth=3, seed=3 if analytic else 4), (48, 36), 256))
    (m0, v0), (m1, v1) = images
    ok, p, threshold = z_test(m0, v0, m1, v1, block=2)
    assert ok, (p, threshold)
    assert abs(m0.mean() - m1.mean()) < 0.01 * m1.mean()
