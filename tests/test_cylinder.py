"""The analytic cylinder (kernels/shapes/cylinder.cl, app/shapes/cylinder.py): its area, points,
normals, uv and dp/du against pbrt-v4's formulas (section 6.3), a ray from inside meeting its far
wall, and the pbrt-v4 and Mitsuba 3 readers' cylinders. The registry's tests
(tests/test_shapes.py) cover its BVH hits, sampling and lighting."""

import math

import numpy as np
import pytest

from pathtrace.scene import load_scene
from pathtrace.shapes import SHAPES
from tests.analytic_shapes import hits_as_pbrt, moved, pbrt_emitter, pbrt_scene, placed_quadric
from tests.test_shapes import shape_hits

RADIUS, Z_MIN, Z_MAX, PHI_MAX = 0.8, -0.4, 1.1, math.radians(300)


def test_area_is_the_wall():
    assert SHAPES["cylinder"].area((RADIUS, Z_MIN, Z_MAX, PHI_MAX)) == pytest.approx(
        (Z_MAX - Z_MIN) * RADIUS * PHI_MAX)


@pytest.mark.parametrize("flip", [False, True])
@pytest.mark.parametrize("uniform", [True, False])
def test_hits_follow_pbrts_formulas(kernels, flip, uniform):
    """Rays from outside and from inside aimed at object points (r cos phi, r sin phi, z) meet
    the wall there (from inside, the ray first crosses no wall: it starts on the axis), with
    pbrt-v4's u = phi / phi_max, v = (z - z_min) / (z_max - z_min), dp/du = phi_max (-y, x, 0)
    moved to the world, and the outward normal moved as a normal (turned by `flip`); beyond
    z_max or phi_max rays miss (no caps)."""
    rng, n = np.random.default_rng(4), 2000
    scene, m, phi = placed_quadric("cylinder", (RADIUS, Z_MIN, Z_MAX, PHI_MAX), uniform, flip, rng, n)
    z = Z_MIN + rng.uniform(0.001, 0.999, n) * (Z_MAX - Z_MIN)
    local = np.column_stack([RADIUS * np.cos(phi), RADIUS * np.sin(phi), z])
    outward = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(n)])
    inside = rng.random(n) < 0.5
    start = np.where(inside[:, None], np.column_stack([np.zeros((n, 2)), z]),
                     local + outward * rng.uniform(0.5, 3, (n, 1)))
    h = hits_as_pbrt(kernels, scene, m, start, local, np.column_stack([phi / PHI_MAX, (z - Z_MIN) / (Z_MAX - Z_MIN)]),
                     PHI_MAX, 3e-5, 3e-4)
    normal = outward @ np.linalg.inv(m[:3, :3])
    normal = (-1 if flip else 1) * normal / np.linalg.norm(normal, axis=1, keepdims=True)
    np.testing.assert_allclose(h["n"], normal, atol=1e-5)
    # above the top, and through the missing sector (from the axis)
    above = local.copy()
    above[: n // 2, 2] = Z_MAX + rng.uniform(0.01, 1, n // 2)
    gap = rng.uniform(PHI_MAX + 0.01, 2 * math.pi - 0.01, n - n // 2)
    above[n // 2:, :2] = RADIUS * np.column_stack([np.cos(gap), np.sin(gap)])
    start = np.column_stack([np.zeros((n, 2)), above[:, 2]])
    assert np.all(np.isnan(shape_hits(kernels, scene, moved(m, start), moved(m, above))["p"][:, 0]))


def test_pbrt_cylinder_orders_its_ends_and_clamps_phimax(tmp_path, capfd):
    """pbrt-v4's Cylinder::Create orders zmin and zmax and clamps phimax to 360; `power` is
    spread over its area 2 pi r (zmax - zmin); ReverseOrientation turns it inside out. (The z
    range is mirrored, under a turned z: from_pbrt.)"""
    c, emission = pbrt_emitter(tmp_path, capfd, 'ReverseOrientation\nShape "cylinder" "float radius" 0.5 '
                               '"float zmin" 2 "float zmax" -1 "float phimax" 400')
    assert c.kind == "cylinder" and c.flip and c.params == pytest.approx((0.5, -2.0, 1.0, 2 * math.pi))
    np.testing.assert_allclose(emission, 10 / (math.pi * 2 * math.pi * 0.5 * 3), rtol=1e-5)


def test_mitsuba_cylinder_runs_from_p0_to_p1(kernels, tmp_path):
    """Mitsuba 3's cylinder (src/shapes/cylinder.cpp): radius about the segment p0 to p1 of its
    to_world, v = the fraction of the way from p0, u a whole turn; flip_normals turns the
    outward normal."""
    path = tmp_path / "c.xml"
    path.write_text('<scene version="3.0.0"><shape type="cylinder"><point name="p0" value="1, 0, 0"/>'
                    '<point name="p1" value="1, 2, 0"/><float name="radius" value="0.5"/>'
                    '<transform name="to_world"><translate value="0, 0, -1"/></transform>'
                    '<boolean name="flip_normals" value="true"/></shape></scene>')
    scene = load_scene(str(path))
    (c,) = scene.shapes
    rng = np.random.default_rng(6)
    y, a = rng.uniform(0.01, 1.99, 300), rng.uniform(0, 2 * math.pi, 300)
    axis = np.column_stack([np.ones(300), y, np.full(300, -1.0)])
    target = axis + 0.5 * np.column_stack([np.cos(a), np.zeros(300), np.sin(a)])
    h = shape_hits(kernels, scene, axis + 3 * (target - axis), target)
    np.testing.assert_allclose(h["p"], target, atol=2e-5)
    np.testing.assert_allclose(h["uv"][:, 1], y / 2, atol=2e-5)
    np.testing.assert_allclose(h["n"], -(target - axis) / 0.5, atol=1e-5)
    assert np.ptp(h["uv"][:, 0]) > 0.9               # u runs round the whole turn


def test_a_pbrt_cylinder_is_textured_at_pbrts_image_coordinates(kernels, tmp_path):
    """pbrt-v4 looks images up at (u, 1 - v) (ImageTexture), and the pbrt reader turns every
    mesh's v round once so that pathtrace's lookup at (u, v) reads the same texel: a pbrt
    cylinder's hit must carry v = 1 - pbrt's (z - zmin) / (zmax - zmin), its front still outward."""
    scene = pbrt_scene(tmp_path, 'Translate 0.3 0 0\n'
                              'Shape "cylinder" "float radius" 0.8 "float zmin" -0.5 "float zmax" 1.5 "float phimax" 300')
    rng, n = np.random.default_rng(7), 500
    phi = rng.uniform(0.01, math.radians(300) - 0.01, n)
    z = rng.uniform(-0.49, 1.49, n)
    wall = np.column_stack([0.8 * np.cos(phi) + 0.3, 0.8 * np.sin(phi), z])
    outward = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(n)])
    h = shape_hits(kernels, scene, wall + 2 * outward, wall)
    np.testing.assert_allclose(h["p"], wall, atol=3e-5)
    np.testing.assert_allclose(h["uv"], np.column_stack([phi / math.radians(300), 1 - (z + 0.5) / 2.0]), atol=2e-5)
    np.testing.assert_allclose(h["n"], outward, atol=1e-5)
