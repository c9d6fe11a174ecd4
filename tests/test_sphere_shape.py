"""The analytic sphere (kernels/shapes/sphere.cl, app/shapes/sphere.py): pbrt-v4's partial sphere
(section 6.2) in its object's space, so that a transform that stretches unevenly makes the
ellipsoid pbrt-v4 intersects, and Mitsuba 3's sphere, which stays round. Its hits, uv, dp/du and
normals against pbrt-v4's formulas, an ellipsoid's and a partial sphere's silhouette against
their closed-form areas (rendered from pbrt files), an emitting ellipsoid lit by next-event
estimation and by paths alone, the sphere range against the kind it stands for, the readers'
spheres (pbrt's `power`, fronts and bad parameters; Mitsuba's round spheres). The registry's
tests (tests/test_shapes.py) cover its BVH hits, area sampling and lighting."""

import math

import numpy as np
import pytest

from pathtrace.cameras import PerspectiveCamera
from pathtrace.errors import UserError
from pathtrace.materials import pack
from pathtrace.materials.bsdf import EMITS_BACK
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import Mesh, SceneBuilder, diffuse, load_scene
from pathtrace.scene import transform
from pathtrace.scene.environment import Environment
from pathtrace.shapes import SHAPES, Shape
from pathtrace.shapes.sphere import TURN_Z
from tests.analytic_shapes import hits_as_pbrt, moved, pbrt_emitter, placed_quadric
from tests.stats import z_test
from tests.test_shapes import one_shape_scene, render, shape_hits

RADIUS, Z_MIN, Z_MAX, PHI_MAX = 0.8, -0.5, 0.3, math.radians(250)
SPHERE = SHAPES["sphere"]


def theta_of(z, r=RADIUS):
    return np.arccos(np.clip(z / r, -1, 1))


def test_pbrts_defaults_order_and_clamps():
    """pbrt-v4's Sphere: zmin and zmax default to -radius and radius, are ordered and clamped to
    [-radius, radius]; phimax is clamped to 360 degrees; the area is phi_max r (z_max - z_min)."""
    assert SPHERE.params_from({}) == pytest.approx((1.0, -1.0, 1.0, 2 * math.pi))
    assert SPHERE.params_from({"radius": 2.5}) == pytest.approx((2.5, -2.5, 2.5, 2 * math.pi))
    assert SPHERE.params_from({"radius": 1.0, "z_min": 0.5, "z_max": -3.0, "phi_max": 400.0}) == \
        pytest.approx((1.0, -1.0, 0.5, 2 * math.pi))
    assert SPHERE.area((RADIUS, Z_MIN, Z_MAX, PHI_MAX)) == pytest.approx(PHI_MAX * RADIUS * (Z_MAX - Z_MIN))
    assert SPHERE.area(SPHERE.params_from({"radius": 2.0})) == pytest.approx(4 * math.pi * 4)


@pytest.mark.parametrize("flip", [False, True])
@pytest.mark.parametrize("uniform", [True, False])
def test_hits_follow_pbrts_formulas(kernels, flip, uniform):
    """Rays from outside and from the centre aimed at object points r (sin theta cos phi,
    sin theta sin phi, cos theta) of a partial sphere meet it there, with pbrt-v4's
    u = phi / phi_max, v = (theta - theta(z_min)) / (theta(z_max) - theta(z_min)), dp/du =
    phi_max (-y, x, 0) moved to the world and the outward normal moved as a normal (turned by
    `flip`); a ray through the missing cap meets the inside of the far wall (pbrt-v4 tests the
    far crossing); rays beyond z_max or phi_max miss."""
    rng, n = np.random.default_rng(4), 2000
    scene, m, phi = placed_quadric("sphere", (RADIUS, Z_MIN, Z_MAX, PHI_MAX), uniform, flip, rng, n)
    z = rng.uniform(Z_MIN + 1e-3, Z_MAX - 1e-3, n)
    theta = theta_of(z)
    outward = np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    local = RADIUS * outward
    inside = rng.random(n) < 0.5
    start = np.where(inside[:, None], 0.0, local + outward * rng.uniform(0.5, 3, (n, 1)))
    t0, t1 = theta_of(Z_MIN), theta_of(Z_MAX)
    h = hits_as_pbrt(kernels, scene, m, start, local, np.column_stack([phi / PHI_MAX, (theta - t0) / (t1 - t0)]),
                     PHI_MAX, 3e-5, 3e-4)
    normal = outward @ np.linalg.inv(m[:3, :3])
    normal = (-1 if flip else 1) * normal / np.linalg.norm(normal, axis=1, keepdims=True)
    np.testing.assert_allclose(h["n"], normal, atol=2e-5)
    # down through the missing cap (z > z_max) onto the inside of the wall below, z = -height
    height = rng.uniform(Z_MAX + 0.01, -Z_MIN - 0.01, n)
    ring = np.sqrt(RADIUS ** 2 - height ** 2)
    below = np.column_stack([ring * np.cos(phi), ring * np.sin(phi), -height])
    h = shape_hits(kernels, scene, moved(m, below * [1, 1, -1] + [0, 0, 2]), moved(m, below))
    np.testing.assert_allclose(h["p"], moved(m, below), atol=3e-5)
    # from the centre to points of the whole sphere above z_max and in the missing sector
    cut_theta = np.concatenate([theta_of(rng.uniform(Z_MAX + 0.01, RADIUS - 0.01, n // 2)), theta[n // 2:]])
    cut_phi = np.concatenate([phi[: n // 2], rng.uniform(PHI_MAX + 0.01, 2 * math.pi - 0.01, n - n // 2)])
    miss = RADIUS * np.column_stack([np.sin(cut_theta) * np.cos(cut_phi), np.sin(cut_theta) * np.sin(cut_phi),
                                     np.cos(cut_theta)])
    assert np.all(np.isnan(shape_hits(kernels, scene, moved(m, np.zeros_like(miss)), moved(m, miss))["p"][:, 0]))


PBRT_SILHOUETTE = """LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic"
Sampler "independent" "integer pixelsamples" 64
Film "rgb" "integer xresolution" 48 "integer yresolution" 48 "string filename" "ellipsoid.png"
WorldBegin
AttributeBegin
AreaLightSource "diffuse" "rgb L" [1 1 1]
{transform}
Shape "sphere" "float radius" 0.45 {params}
AttributeEnd
"""


def silhouette_area_zoned(z0, z1, phi_max, r=0.45):
    """The area the zone z0 <= z <= z1 (0 <= z0) of phi_max covers seen along z: the ring of
    radii sqrt(r^2 - z1^2) to sqrt(r^2 - z0^2)."""
    return phi_max / 2 * (z1 ** 2 - z0 ** 2)


@pytest.mark.parametrize("transform_line, params, area", [
    # the silhouette of M (the unit ball) along d is pi |det M| |M^-1 d|: the cylinder of the
    # ball along M^-1 d, moved by M
    ("Rotate 35 1 1 0 Scale 1 2 0.6", "",
     math.pi * 0.45 ** 2 * 1.2 * float(np.linalg.norm(np.linalg.solve(
         (transform.rotation([1, 1, 0], 35) @ transform.scaling([1, 2, 0.6]))[:3, :3], [0, 0, 1])))),
    # seen along its stretched z: |det M| / |M z| times the zone's own silhouette
    ("Scale 1 2 1", '"float zmin" 0.1 "float zmax" 0.4 "float phimax" 250',
     2 * silhouette_area_zoned(0.1, 0.4, math.radians(250)))])
def test_an_ellipsoid_covers_its_closed_form_area(backend, tmp_path, transform_line, params, area):
    """pbrt files of an emitting sphere (L = 1) under a Scale 1 2 1 seen by an orthographic
    camera over a black world: the image's mean times the film's 2 x 2 units is the silhouette's
    area, the ellipsoid pbrt-v4 intersects (a Z-test against the closed form), a partial
    sphere's too (the outside of the zone z_min to z_max, phi_max of a turn)."""
    path = tmp_path / "e.pbrt"
    path.write_text(PBRT_SILHOUETTE.format(transform=transform_line, params=params))
    scene = load_scene(str(path))
    assert not scene.meshes and len(scene.spheres) == 0 and [s.kind for s in scene.shapes] == ["sphere"]
    r = Renderer(backend, scene, 48, 48)
    r.add_samples(64)
    r.finish()
    image, var = r.mean()[..., :1], r.variance()[..., :1] / 64
    covered = np.array([[[4 * image.mean()]]])
    ok, p, threshold = z_test(covered, np.array([[[16 * var.sum() / image.size ** 2]]]), np.array([[[area]]]))
    assert ok, (covered, area, p)


def test_an_emitting_ellipsoid_with_nee_and_the_light_tree_matches_paths_alone(backend):
    """A partial sphere under a non-uniform scale, emitting over a diffuse floor: next-event
    estimation (its area sampling, density |det M| |M^-T n| per object area) and the light tree
    against paths alone, per-pixel Z-tests."""
    def scene(light_sampler):
        b = SceneBuilder()
        floor = np.array([[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]], np.float32)
        b.add_mesh(Mesh("floor", floor, np.array([[0, 1, 2], [0, 2, 3]], np.int32), None, b.material(diffuse(0.6))))
        lamp = int(b.materials.add_rows(pack("black", {}, emission=np.array([[4.0, 4.0, 4.0]])))[0])
        m = transform.translation([0, 1.2, 0]) @ transform.rotation([1, 0, 1], 60) @ transform.scaling([0.4, 0.9, 0.6])
        b.add_shape(Shape("lamp", "sphere", (1.0, -0.6, 0.8, math.radians(290)), m, lamp))
        return b.build("ellipsoid light", camera=PerspectiveCamera([0, 2.2, 4.5], [0, 0.5, 0], [0, 1, 0], 50.0),
                       environment=Environment.constant((0, 0, 0))).with_settings(light_sampler=light_sampler,
                                                                                  max_depth=3)
    # Paths alone find the lamp from the floor's far corner by chance only: at 4096 samples per
    # pixel one run's 4x4 block there met it not once (a sample variance that has seen no hit;
    # p 3e-11 against NEE's 0.00034 a pixel), so they draw 8192; next-event estimation, whose
    # variance is a small fraction of theirs, 2048 (as tests/test_shapes.py's emitting shapes)
    spp, others = 8192, 2048
    m0, v0 = render(backend, scene("power"), spp, nee=False, seed=1)
    assert m0.mean() > 0.02
    for sampler in ("power", "tree"):
        m1, v1 = render(backend, scene(sampler), others, nee=True, seed=2)
        ok, p, threshold = z_test(m0, v0 / spp, m1, v1 / others, block=4)
        assert ok, (sampler, p, threshold)


def test_the_sphere_range_meets_rays_as_the_analytic_sphere_it_stands_for(kernels):
    """SceneBuilder.add_shape keeps a whole, outward, similarity-placed sphere whose rotation is
    TURN_Z in the sphere range (fast_range): the same rays meet the range's sphere and the
    analytic one at the same points, with the same normals, uv (Mitsuba's, about the world's
    axes) and dp/du."""
    m = transform.translation([0.2, 0.5, -0.3]) @ transform.scaling([0.7] * 3) @ TURN_Z
    shape = Shape("ball", "sphere", (1.0, -1.0, 1.0, 2 * math.pi), m, 0)
    fast, analytic = SceneBuilder(), SceneBuilder()
    for b in (fast, analytic):
        b.material(diffuse(0.5))
    fast.add_shape(shape)
    analytic.shapes.append(shape)
    assert len(fast.spheres) == 1 and not fast.shapes
    rng = np.random.default_rng(8)
    origins = rng.normal(size=(3000, 3)) * 3
    aim = m[:3, 3] + rng.normal(size=(3000, 3)) * 0.3 - origins
    targets = origins + aim / np.linalg.norm(aim, axis=1, keepdims=True)      # the range takes unit directions
    a, b = (shape_hits(kernels, builder.build("ball"), origins, targets) for builder in (fast, analytic))
    assert np.isnan(a["p"][:, 0]).sum() == np.isnan(b["p"][:, 0]).sum() < 300
    # float32 rounding apart: the analytic sphere's point comes back through its angles' sin and cos
    for key, tolerance in (("p", 1e-5), ("n", 1e-5), ("uv", 1e-5), ("dpdu", 1e-4)):
        np.testing.assert_allclose(a[key], b[key], atol=tolerance, err_msg=key)


def test_pbrt_power_is_spread_over_the_object_space_area(tmp_path, capfd):
    """pbrt-v4's DiffuseAreaLight::Create divides `power` by pi times the shape's Area(), which
    for a sphere is phi_max r (z_max - z_min) in its object's space (src/pbrt/shapes.h): a Scale
    does not enter it. The partial sphere's uniform scale keeps it in the analytic kind."""
    s, emission = pbrt_emitter(tmp_path, capfd, 'Scale 2 2 2\nShape "sphere" "float radius" 0.5 "float zmin" -0.2 '
                               '"float phimax" 180')
    assert s.kind == "sphere" and s.params == pytest.approx((0.5, -0.5, 0.2, math.pi))     # z turned round
    np.testing.assert_allclose(emission, 10 / (math.pi * math.pi * 0.5 * 0.7), rtol=1e-5)


@pytest.mark.parametrize("params, field", [('"float radius" -1', "radius"),
                                           ('"float zmin" 2 "float zmax" 3', "z_min"),
                                           ('"float phimax" 0', "phi_max"),
                                           ('"float phimax" -20', "phi_max")])
def test_a_bad_pbrt_sphere_is_one_line_naming_the_file_line_and_field(tmp_path, params, field):
    path = tmp_path / "bad.pbrt"
    path.write_text(PBRT_SILHOUETTE.format(transform="", params="").replace('"float radius" 0.45 ', params + " "))
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    message = str(e.value)
    assert "\n" not in message and "bad.pbrt:9" in message and field in message, message


def test_pbrt_spheres_are_analytic_with_pbrts_front(tmp_path, capfd):
    """ReverseOrientation and a transform that swaps handedness turn a pbrt sphere's front
    (pbrt-v4's Sphere: reverseOrientation ^ transformSwapsHandedness), a two-sided light emits
    from both sides, and an instance under a non-uniform scale gives the ellipsoid, all without
    a warning."""
    path = tmp_path / "s.pbrt"
    path.write_text("""LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 45
Film "rgb" "integer xresolution" 16 "integer yresolution" 16 "string filename" "x.exr"
WorldBegin
AttributeBegin
ReverseOrientation
Shape "sphere" "float radius" 0.5
AttributeEnd
AttributeBegin
Scale -1 1 1
AreaLightSource "diffuse" "rgb L" [1 1 1] "bool twosided" true
Shape "sphere" "float zmax" 0.5
AttributeEnd
ObjectBegin "ball"
Shape "sphere" "float radius" 0.3
ObjectEnd
AttributeBegin
Scale 1 2 1
ObjectInstance "ball"
AttributeEnd
""")
    scene = load_scene(str(path))
    assert "warning" not in capfd.readouterr().err
    assert len(scene.spheres) == 0 and not scene.meshes
    reversed_, mirrored, instanced = scene.shapes
    assert reversed_.flip and mirrored.flip and not instanced.flip
    assert mirrored.params == pytest.approx((1.0, -0.5, 1.0, 2 * math.pi))          # z turned round: from_pbrt
    assert scene.materials.rows["flags"][mirrored.material] & EMITS_BACK
    np.testing.assert_allclose(instanced.to_world[:3, :3], np.diag([1, 2, -1]))


def test_mitsuba_spheres_stay_round_with_mitsubas_uv(kernels, tmp_path, capfd):
    """Mitsuba 3's sphere (src/shapes/sphere.cpp): to_world translate(center) scale(radius), its
    uv (phi / 2 pi, theta / pi) about the axes of its to_world's rotation; flip_normals turns
    the normal inwards; an uneven scale is warned of and kept round, of radius |to_world (1, 0,
    0)|, as Mitsuba keeps it; an unrotated one stays in the sphere range."""
    path = tmp_path / "s.xml"
    path.write_text('<scene version="3.0.0">'
                    '<shape type="sphere"><point name="center" value="1, 0, 0"/><float name="radius" value="0.5"/>'
                    '<transform name="to_world"><rotate x="1" angle="90"/><translate value="0, 2, 0"/></transform>'
                    '<boolean name="flip_normals" value="true"/></shape>'
                    '<shape type="sphere"><transform name="to_world"><scale value="0.5, 1, 2"/>'
                    '<translate value="0, 0, -5"/></transform></shape>'
                    '<shape type="sphere"><point name="center" value="0, 5, 0"/></shape></scene>')
    scene = load_scene(str(path))
    assert "renders it round, of radius" in capfd.readouterr().err
    np.testing.assert_allclose(scene.spheres, [[0, 0, -5, 0.5], [0, 5, 0, 1]])
    (rotated,) = scene.shapes
    rng = np.random.default_rng(3)
    theta, phi = rng.uniform(0.05, math.pi - 0.05, 400), rng.uniform(0.01, 2 * math.pi - 0.01, 400)
    local = np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    rotation = transform.rotation([1, 0, 0], 90)[:3, :3]
    centre = rotation @ [1, 0, 0] + [0, 2, 0]
    target = centre + 0.5 * local @ rotation.T
    h = shape_hits(kernels, one_shape_scene(rotated), centre + 3 * (target - centre), target)
    np.testing.assert_allclose(h["p"], target, atol=2e-5)
    np.testing.assert_allclose(h["uv"], np.column_stack([phi / (2 * math.pi), theta / math.pi]), atol=2e-5)
    np.testing.assert_allclose(h["n"], -(target - centre) / 0.5, atol=1e-5)
