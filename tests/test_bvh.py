"""The BVH: its structure, and the nearest hit it finds against brute force over all spheres."""

import numpy as np
import pytest

from app.bvh import MAX_DEPTH, build_bvh

SOURCE = """
kernel void nearest(global const BVHNode *nodes, global const Sphere *spheres, int n_spheres,
                    global const float4 *o, global const float4 *d, int skip_first,
                    global float *t_bvh, global int *i_bvh, global float *t_all, global int *i_all)
{
    int k = get_global_id(0);
    float3 org = o[k].xyz, dir = normalize(d[k].xyz);
    int skip = skip_first ? 0 : -1;
    Hit h = intersect_scene(nodes, spheres, org, dir, INFINITY, skip);
    t_bvh[k] = h.t; i_bvh[k] = h.sphere;
    Hit b = {INFINITY, -1};
    intersect_leaf(spheres, 0, n_spheres, org, dir, skip, &b);
    t_all[k] = b.t; i_all[k] = b.sphere;
}
"""


def random_spheres(rng, n, radius_range=(0.05, 1.5)):
    return np.column_stack([rng.uniform(-10, 10, (n, 3)), rng.uniform(*radius_range, n)]).astype(np.float32)


def leaves(bvh):
    c = bvh.nodes["child"]
    return c["index"][c["count"] > 0], c["count"][c["count"] > 0]


@pytest.mark.parametrize("n", [1, 2, 3, 7, 100, 5000])
def test_every_sphere_in_one_leaf_and_inside_its_boxes(n):
    rng = np.random.default_rng(n)
    spheres = random_spheres(rng, n)
    bvh = build_bvh(spheres)
    assert sorted(bvh.order.tolist()) == list(range(n))
    first, count = leaves(bvh)
    covered = np.concatenate([np.arange(f, f + c) for f, c in zip(first, count)])
    if n == 1:
        covered = np.unique(covered)   # the lone sphere sits in both root slots
    assert sorted(covered.tolist()) == list(range(n))
    ordered = spheres[bvh.order]
    for node in bvh.nodes:
        for c in node["child"]:
            if c["count"]:
                s = ordered[c["index"]:c["index"] + c["count"]]
                assert np.all(s[:, :3] - s[:, 3:] >= c["lo"]) and np.all(s[:, :3] + s[:, 3:] <= c["hi"])
    assert bvh.depth <= MAX_DEPTH


def test_children_boxes_nest():
    bvh = build_bvh(random_spheres(np.random.default_rng(3), 3000))
    c = bvh.nodes["child"]
    for k in range(len(bvh.nodes)):
        for s in range(2):
            if c["count"][k, s] == 0:
                inner = c[c["index"][k, s]]
                assert np.all(inner["lo"] >= c["lo"][k, s]) and np.all(inner["hi"] <= c["hi"][k, s])


def test_identical_centres_still_split():
    spheres = np.tile([1.0, 2.0, 3.0, 0.5], (1000, 1)).astype(np.float32)
    bvh = build_bvh(spheres)
    _, count = leaves(bvh)
    assert count.max() <= 4 and bvh.depth < 20


def upload(kernels, spheres):
    bvh = build_bvh(spheres)
    return bvh, spheres[bvh.order]


@pytest.mark.parametrize("n,seed", [(1, 0), (2, 1), (5, 2), (64, 3), (1000, 4), (8000, 5)])
def test_nearest_hit_matches_brute_force(kernels, n, seed):
    rng = np.random.default_rng(seed)
    spheres = random_spheres(rng, n)
    bvh, ordered = upload(kernels, spheres)
    rays = 20000
    # origins inside the cloud and outside it, all directions
    o = np.column_stack([rng.uniform(-15, 15, (rays, 3)), np.zeros(rays)]).astype(np.float32)
    d = rng.normal(size=(rays, 3))
    aimed = rng.integers(0, n, rays // 2)    # half the rays aim at a sphere
    d[: rays // 2] = spheres[aimed, :3] - o[: rays // 2, :3]
    d = np.column_stack([d, np.zeros(rays)]).astype(np.float32)
    out = [np.zeros(rays, np.float32), np.zeros(rays, np.int32), np.zeros(rays, np.float32), np.zeros(rays, np.int32)]
    for skip in (0, 1):
        kernels(SOURCE)("nearest", rays, bvh.nodes, ordered, np.int32(n), o, d, np.int32(skip), *out)
        t_bvh, i_bvh, t_all, i_all = out
        np.testing.assert_array_equal(t_bvh, t_all)
        same = i_bvh == i_all
        # different indices only where two spheres are met at exactly the same t
        assert np.all(same | (t_bvh == t_all))
        if not skip:
            assert np.any(np.isfinite(t_all))
