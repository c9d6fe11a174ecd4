"""Ray-sphere intersection against float64 closed forms, edge cases included."""

import numpy as np
import pytest

SOURCE = """
kernel void hit_sphere(global const float4 *spheres, global const float4 *o, global const float4 *d,
                       global float *t)
{
    int i = get_global_id(0);
    t[i] = intersect_range_sphere(spheres[i], o[i].xyz, normalize(d[i].xyz), INFINITY);
}
"""


def reference_t(s, o, d):
    """Nearest positive root in float64 (INF if none)."""
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    f = o - s[:, :3]
    b = np.sum(f * d, axis=1)
    c = np.sum(f * f, axis=1) - s[:, 3] ** 2
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0))
    t0, t1 = -b - root, -b + root
    t = np.where(t0 > 0, t0, np.where(t1 > 0, t1, np.inf))
    return np.where(disc >= 0, t, np.inf)


def run(kernels, s, o, d):
    pad = lambda a: np.column_stack([a, np.zeros(len(a))]).astype(np.float32)  # noqa: E731
    t = np.zeros(len(s), np.float32)
    kernels(SOURCE)("hit_sphere", len(s), np.asarray(s, np.float32), pad(o), pad(d), t)
    return t


def test_random_rays_match_float64(kernels):
    rng = np.random.default_rng(1)
    n = 20000
    s = np.column_stack([rng.uniform(-5, 5, (n, 3)), rng.uniform(0.1, 3, n)])
    o = rng.uniform(-10, 10, (n, 3))
    d = rng.normal(size=(n, 3))
    t = run(kernels, s, o, d)
    ref = reference_t(s.astype(np.float32).astype(np.float64), o.astype(np.float32), d.astype(np.float32))
    both = np.isfinite(ref) & np.isfinite(t)
    # hits and misses agree except for rays grazing the silhouette
    assert np.mean(np.isfinite(ref) != np.isfinite(t)) < 1e-3
    np.testing.assert_allclose(t[both], ref[both], rtol=1e-4, atol=1e-4)


def test_ray_from_inside_meets_the_far_side(kernels):
    s = np.array([[0, 0, 0, 2.0]])
    t = run(kernels, s, np.array([[0.5, 0, 0]]), np.array([[1.0, 0, 0]]))
    assert t[0] == pytest.approx(1.5, rel=1e-6)


def test_sphere_behind_is_missed(kernels):
    s = np.array([[0, 0, -5, 1.0]])
    t = run(kernels, s, np.zeros((1, 3)), np.array([[0, 0, 1.0]]))
    assert np.isinf(t[0])


def test_far_ground_sphere_hit_lies_on_its_surface(kernels):
    """The r = 1000 ground of `simple` seen from its camera, down to shallow angles (the horizon
    dips 0.063 rad below level there): the hit point lies on the sphere to float precision."""
    n = 2000
    rng = np.random.default_rng(2)
    s = np.tile([0, -1000, 0, 1000.0], (n, 1))
    o = np.tile([0, 2, 9.0], (n, 1))
    d = np.column_stack([rng.uniform(-1, 1, n), -10 ** rng.uniform(-1, 0, n), -np.ones(n)])
    t = run(kernels, s, o, d).astype(np.float64)
    dn = d / np.linalg.norm(d, axis=1, keepdims=True)
    p = o + t[:, None] * dn
    assert np.all(np.isfinite(t))
    assert np.max(np.abs(np.linalg.norm(p - s[:, :3], axis=1) - 1000)) < 1e-3
