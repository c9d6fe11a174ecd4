"""Ray-triangle intersection (kernels/shapes/triangle.cl) against float64 closed forms, its
watertightness on a closed mesh, and robust ray spawning (kernels/spawn.cl) on triangles and
spheres: a ray leaving a surface never meets that surface again by error."""

import numpy as np
import pytest

from pathtrace.compiler.compiled import compile_scene
from pathtrace.scene import Mesh, SceneBuilder, diffuse
from tests.conftest import layout_features, scene_arrays
from tests.geometry import height_field, icosphere

SOURCE = """
kernel void edge_pairs(global const float4 *q, global float2 *out)
{
    int i = get_global_id(0);
    float4 v = q[i];
    out[i] = (float2)(edge_function(v.x, v.y, v.z, v.w), edge_function(v.z, v.w, v.x, v.y));
}
kernel void surface_point(global const Triangle *tri, global const float2 *b, global float4 *p,
                          global float4 *error)
{
    int i = get_global_id(0);
    float3 point, bound, ng, ns;
    triangle_surface(&tri[i], (const global float4 *)0, b[i].x, b[i].y, &point, &bound, &ng, &ns);
    p[i] = (float4)(point, 0.0f);
    error[i] = (float4)(bound, 0.0f);
}
kernel void hit_triangle(global const Triangle *tri, global const float4 *o, global const float4 *d,
                         global float4 *out)
{
    int i = get_global_id(0);
    float3 dir = normalize(d[i].xyz);
    float3 rx, ry, rz;
    triangle_shear(dir, &rx, &ry, &rz);
    float b1 = 0.0f, b2 = 0.0f;
    float t = intersect_triangle(&tri[i], o[i].xyz, rx, ry, rz, INFINITY, &b1, &b2);
    out[i] = (float4)(t, b1, b2, 0.0f);
}
kernel void trace(SCENE_KERNEL_ARGS, int num_spheres, global const float4 *o, global const float4 *d,
                  global float4 *out)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    int i = get_global_id(0);
    Hit h = intersect_scene(&sc, o[i].xyz, normalize(d[i].xyz), INFINITY, -1);
    out[i] = (float4)(h.t, as_float(h.prim), 0.0f, 0.0f);
}
/* Shoots ray i at the scene, then spawns a second ray from the hit point in direction w[i]
 * (flipped to leave on the side of the geometric normal given by side[i]: +1 the front
 * hemisphere, -1 the back one): returns the first prim, the second ray's hit and prim. */
kernel void respawn(SCENE_KERNEL_ARGS, int num_spheres, global const float4 *o, global const float4 *d,
                    global const float4 *w, float side, global float4 *out)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    int i = get_global_id(0);
    float3 dir = normalize(d[i].xyz);
    Hit h = intersect_scene(&sc, o[i].xyz, dir, INFINITY, -1);
    if (h.prim < 0) { out[i] = (float4)(-1.0f); return; }
    Surface s = surface_at(&sc, &h, o[i].xyz, dir);
    float3 n = dot(s.ng, dir) < 0.0f ? s.ng : -s.ng;       /* the side the ray came from */
    float3 wi = normalize(w[i].xyz);
    if (dot(wi, n) * side < 0.0f) wi = -wi;
    Hit h2 = intersect_scene(&sc, offset_ray_origin(s.p, s.offset, s.ng, wi), wi, INFINITY, h.prim);
    out[i] = (float4)(as_float(h.prim), h2.t, as_float(h2.prim), 0.0f);
}
"""


def f4(a):
    a = np.asarray(a, np.float32).reshape(-1, 3)
    return np.column_stack([a, np.zeros(len(a), np.float32)])


def triangles(corners):
    from pathtrace.device.types import TRIANGLE
    t = np.zeros(len(corners), TRIANGLE)
    for k, f in enumerate(("v0", "v1", "v2")):
        t[f][:, :3] = corners[:, k]
    t["v0"][:, 3] = np.full(len(corners), -1, np.int32).view(np.float32)
    return t


def reference(corners, o, d):
    """Moller-Trumbore in float64: t (inf on a miss) and the barycentrics of v1, v2."""
    c = corners.astype(np.float64)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    e1, e2 = c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]
    p = np.cross(d, e2)
    det = np.sum(e1 * p, axis=1)
    s = o - c[:, 0]
    u = np.sum(s * p, axis=1) / det
    q = np.cross(s, e1)
    v = np.sum(d * q, axis=1) / det
    t = np.sum(e2 * q, axis=1) / det
    hit = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return np.where(hit, t, np.inf), u, v


def run_triangles(kernels, corners, o, d):
    out = np.zeros((len(corners), 4), np.float32)
    kernels(SOURCE)("hit_triangle", len(corners), triangles(corners), f4(o), f4(d), out)
    return out


def test_random_rays_match_float64(kernels):
    rng = np.random.default_rng(4)
    n = 20000
    corners = rng.uniform(-2, 2, (n, 3, 3)).astype(np.float32)
    o = rng.uniform(-6, 6, (n, 3)).astype(np.float32)
    target = corners.mean(axis=1) + rng.normal(scale=0.8, size=(n, 3))   # near misses too
    d = (target - o).astype(np.float32)
    out = run_triangles(kernels, corners, o.astype(np.float64), d.astype(np.float64))
    t_ref, u, v = reference(corners, o.astype(np.float64), d.astype(np.float64))
    # hits and misses agree except for rays within float precision of an edge
    margin = np.minimum(np.minimum(u, v), 1 - u - v)
    clear = np.abs(margin) > 1e-4
    assert np.array_equal(np.isfinite(out[clear, 0]), np.isfinite(t_ref[clear]))
    both = np.isfinite(t_ref) & np.isfinite(out[:, 0]) & clear
    assert both.sum() > 2000
    np.testing.assert_allclose(out[both, 0], t_ref[both], rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(out[both, 1], u[both], atol=1e-4)
    np.testing.assert_allclose(out[both, 2], v[both], atol=1e-4)


def test_edges_and_vertices_are_hit_from_both_sides(kernels):
    """Rays through an edge's midpoint and through a vertex, from the front and from behind: a
    shared edge belongs to the triangle (inclusive test), whichever side the ray comes from."""
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    points = np.array([[0.5, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0], [0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    corners = np.repeat(tri[None], 2 * len(points), axis=0)
    o = np.concatenate([points + [0, 0, 2], points - [0, 0, 2]])
    d = np.concatenate([np.tile([0, 0, -1.0], (len(points), 1)), np.tile([0, 0, 1.0], (len(points), 1))])
    out = run_triangles(kernels, corners, o, d)
    np.testing.assert_allclose(out[:, 0], 2.0, rtol=1e-6)


def test_misses_behind_parallel_and_beside(kernels):
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    corners = np.repeat(tri[None], 3, axis=0)
    o = np.array([[0.2, 0.2, -1], [0.2, 0.2, 0.5], [0.6, 0.6, 1]], np.float32)   # behind, parallel, beside
    d = np.array([[0, 0, -1], [1, 0, 0], [0, 0, -1]], np.float32)
    out = run_triangles(kernels, corners, o, d)
    assert np.all(np.isinf(out[:, 0]))


def mesh_scene(vertices, faces, spheres=()):
    b = SceneBuilder()
    m = b.material(diffuse(0.5))
    b.add_mesh(Mesh("mesh", np.asarray(vertices, np.float32), np.asarray(faces, np.int32), None, m))
    for s in spheres:
        b.add_sphere(s[:3], s[3], m)
    return compile_scene(b.build("test"))


def trace(kernels, compiled, o, d):
    out = np.zeros((len(o), 4), np.float32)
    kernels(SOURCE, layout_features(compiled))("trace", len(o), *scene_arrays(compiled),
                                               np.int32(compiled.num_spheres), f4(o), f4(d), out)
    return out[:, 0], out[:, 1].view(np.int32)


def test_closed_mesh_is_watertight(kernels):
    """200,000 rays from inside a subdivided icosahedron, many aimed exactly at its vertices and
    edge midpoints: every one meets the mesh."""
    v, f = icosphere(3, radius=2.0)
    compiled = mesh_scene(v, f)
    rng = np.random.default_rng(5)
    n = 200_000
    o = rng.normal(size=(n, 3)) * 0.3
    targets = np.concatenate([v[f[:, 0]], (v[f[:, 0]] + v[f[:, 1]]) / 2])
    d = rng.normal(size=(n, 3))
    d[: n // 2] = targets[rng.integers(0, len(targets), n // 2)] - o[: n // 2]
    t, prim = trace(kernels, compiled, o, d)
    assert np.all(np.isfinite(t)) and np.all(prim >= 0)


def respawn(kernels, compiled, o, d, w, side):
    out = np.zeros((len(o), 4), np.float32)
    kernels(SOURCE, layout_features(compiled))("respawn", len(o), *scene_arrays(compiled),
                                               np.int32(compiled.num_spheres), f4(o), f4(d), f4(w),
                                               np.float32(side), out)
    return out[:, 0].view(np.int32), out[:, 1], out[:, 2].view(np.int32)


@pytest.mark.parametrize("radius", [1e-3, 1.0, 1e4])
def test_rays_leaving_a_sphere_never_meet_it_again(kernels, radius):
    """Outward rays from points all over a sphere miss it (it is convex); inward rays meet its
    far side, a chord away, never the point they leave."""
    centre = np.array([3.0, -2.0, 1.0]) * radius
    compiled = mesh_scene(*icosphere(0, 0.01, (100, 100, 100)), spheres=[np.append(centre, radius)])
    rng = np.random.default_rng(6)
    n = 50_000
    u = rng.normal(size=(n, 3))
    o = centre + 3 * radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    d = centre + rng.uniform(-0.9, 0.9, (n, 3)) * radius / np.sqrt(3) - o
    w = rng.normal(size=(n, 3))
    first, t, second = respawn(kernels, compiled, o, d, w, side=1.0)
    sphere = compiled.num_spheres - 1
    assert np.all(first == sphere)
    assert np.all(second != sphere), f"{np.count_nonzero(second == sphere)} outward rays met the sphere again"
    first, t, second = respawn(kernels, compiled, o, d, w, side=-1.0)
    assert np.all(second == sphere)
    assert t.min() > 1e-3 * radius     # a chord, not a self-hit (grazing chords are short but not 0)


def test_rays_leaving_a_concave_mesh_never_meet_their_own_triangle(kernels):
    """From points all over a bumpy height field, rays into the front hemisphere may meet other
    triangles (it is concave) but never the one they leave."""
    v, f = height_field(32)
    compiled = mesh_scene(v * 10, f)
    rng = np.random.default_rng(7)
    n = 100_000
    o = np.column_stack([rng.uniform(-9, 9, n), np.full(n, 30.0), rng.uniform(-9, 9, n)])
    d = np.column_stack([rng.normal(scale=0.05, size=n), -np.ones(n), rng.normal(scale=0.05, size=n)])
    w = rng.normal(size=(n, 3))
    first, t, second = respawn(kernels, compiled, o, d, w, side=1.0)
    hit = first >= 0
    assert hit.mean() > 0.9
    assert np.all(second[hit] != first[hit])
    assert np.any(hit & (second >= 0))      # the bumps do shadow one another


def test_a_hit_point_lies_within_its_error_bound(kernels):
    """The point a hit reports is the barycentric interpolation, within the error bound it
    carries (pbrt-v4's gamma(7) sum |b_i v_i|) of the exact point, on triangles of every scale
    and far from the origin; no scene-scale nudge (it moved points 1e-4 of the way to the
    centroid: 0.14 units on a 2000-unit quad)."""
    rng = np.random.default_rng(3)
    n = 20_000
    scale = 10.0 ** rng.uniform(-3, 3.5, (n, 1, 1))
    corners = (rng.uniform(-1, 1, (n, 3, 3)) * scale + rng.uniform(-1e3, 1e3, (n, 1, 3))).astype(np.float32)
    b = rng.dirichlet((1, 1, 1), n)
    b[: n // 4, 0] = 0.0                                     # points on an edge
    b[: n // 4] /= b[: n // 4].sum(axis=1, keepdims=True)
    bary = b[:, 1:].astype(np.float32)
    p, error = np.zeros((n, 4), np.float32), np.zeros((n, 4), np.float32)
    kernels(SOURCE)("surface_point", n, triangles(corners), bary, p, error)
    b0 = (np.float32(1) - bary[:, 0]) - bary[:, 1]            # as the kernel rounds it
    weights = np.column_stack([b0, bary]).astype(np.float64)
    exact = np.einsum("nk,nkc->nc", weights, corners.astype(np.float64))
    assert np.all(np.abs(p[:, :3] - exact) <= error[:, :3]), np.max(np.abs(p[:, :3] - exact) / error[:, :3])


def test_rays_into_a_concave_corner_meet_the_other_wall(kernels):
    """A floor and a wall of 2000 units meeting at a right angle, seen from inside: rays from
    floor points within a hair of the corner (and on it) towards the wall all meet the wall; the
    skipped triangle they leave is the only one a ray does not test."""
    floor = [[-1000, 0, -1000], [1000, 0, -1000], [1000, 0, 1000], [-1000, 0, 1000]]
    wall = [[-1000, 0, -1000], [-1000, 2000, -1000], [1000, 2000, -1000], [1000, 0, -1000]]
    v = np.array(floor + wall, np.float64)
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 6, 5], [4, 7, 6]])       # floor up, wall facing +z
    compiled = mesh_scene(v, f)
    rng = np.random.default_rng(9)
    n = 50_000
    gap = np.concatenate([np.zeros(n // 2), 10.0 ** rng.uniform(-6, 0, n - n // 2)])
    x = rng.uniform(-900, 900, n)
    targets = np.column_stack([x, np.zeros(n), -1000 + gap])
    o = targets + np.column_stack([rng.normal(size=n), np.full(n, 50.0), rng.uniform(1, 50, n)])
    w = np.column_stack([rng.normal(scale=0.3, size=n), rng.uniform(0.05, 1, n), -np.ones(n)])
    first, t, second = respawn(kernels, compiled, o, targets - o, w, side=1.0)
    on_floor = np.all(compiled.triangles[["v0", "v1", "v2"]].view((np.float32, 12))[:, 1::4] == 0, axis=1)
    floor = np.flatnonzero(on_floor)
    from_floor = np.isin(first, floor)            # the first ray may meet the corner on the wall
    assert from_floor.mean() > 0.6
    wall_hit = (second >= 0) & ~np.isin(second, floor)
    assert wall_hit[from_floor].all(), (np.mean(~wall_hit[from_floor]), gap[from_floor & ~wall_hit][:5])


def test_edge_functions_of_a_shared_edge_have_exact_opposite_signs(kernels):
    """Watertightness rests on this: the two triangles of an edge compute its edge function with
    the corners swapped, and must see the ray on exactly opposite sides of it (or both on it).
    edge_function's sign is the exact value's, from float64 (where products of floats are exact
    and a difference rounds to the right sign), and the value within Kahan's bound of 2 ulp. A
    device that fused the rounded product into a multiply-add (FP_CONTRACT, -cl-mad-enable)
    would lose the error term. Run on each device (PATHTRACE_TEST_DEVICE): coordinates of every
    scale, near-cancelling pairs, where rounding shows first, and exactly cancelling ones."""
    rng = np.random.default_rng(17)
    n = 1_000_000
    q = (rng.uniform(-1, 1, (n, 4)) * 10.0 ** rng.uniform(-6, 6, (n, 1))).astype(np.float32)
    q[: n // 2, 2:] = q[: n // 2, :2] * np.float32(1 + 1e-6) + q[: n // 2, 2:] * np.float32(1e-4)
    q[n // 2: n // 2 + n // 10, 2:] = q[n // 2: n // 2 + n // 10, :2] * np.float32(4)
    out = np.zeros((n, 2), np.float32)
    kernels(SOURCE)("edge_pairs", n, q, out)
    a = q.astype(np.float64)
    exact = a[:, 0] * a[:, 3] - a[:, 1] * a[:, 2]
    assert np.array_equal(np.sign(out[:, 0]), np.sign(exact))
    assert np.array_equal(np.sign(out[:, 1]), -np.sign(exact))
    assert np.count_nonzero(exact == 0) >= n // 10
    assert np.all(np.abs(out - exact[:, None] * [1, -1]) <= 2 * 2.0 ** -24 * np.abs(exact)[:, None])
