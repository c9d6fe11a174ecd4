"""The BVH over spheres and triangles: its structure, and the nearest hit it finds against brute
force over all primitives (exact t), on random spheres, triangle soups, meshes with coincident
and degenerate triangles, mixed scenes, and every primitive at one point."""

import os
import re
import subprocess
import sys
import threading

import numpy as np
import pyopencl as cl
import pytest

import pathtrace.compiler.builder as builder_module
import pathtrace.compiler.bvh as bvh_module
import pathtrace.compiler.bvh_cache as bvh_cache
import pathtrace.compiler.compiled as compiled_module

from pathtrace.compiler.builder import MAX_DEPTH, MAX_LEAF_SIZE, TRAVERSAL_COST, builder_for
from pathtrace.compiler.bvh import RADIUS, build_bvh
from pathtrace.compiler.compiled import compile_scene
from pathtrace.compiler.host_bvh import build_on_host
from pathtrace.device.features import LONE_MAX
from pathtrace.device.opencl import keeps_own_cache
from pathtrace.resources import resource_dir
from pathtrace.scene import Mesh, SceneBuilder, diffuse
from tests.conftest import ROOT, layout_features, scene_arrays

SOURCE = """
kernel void nearest(SCENE_KERNEL_ARGS, int num_spheres, int num_triangles,
                    global const float4 *o, global const float4 *d,
                    global float *t_bvh, global int *i_bvh, global float *t_all, global int *i_all)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    int k = get_global_id(0);
    float3 org = o[k].xyz, dir = normalize(d[k].xyz);
    Hit h = intersect_scene(&sc, org, dir, INFINITY, -1);
    t_bvh[k] = h.t; i_bvh[k] = h.prim;
    Hit b = {INFINITY, -1, 0.0f, 0.0f};
    intersect_spheres(&sc, 0, num_spheres, org, dir, 0, &b);
    intersect_triangles(&sc, 0, num_triangles, org, dir, -1, 0, &b);
    t_all[k] = b.t; i_all[k] = b.prim;
}

kernel void blocked(SCENE_KERNEL_ARGS, int num_spheres, global const float4 *o, global const float4 *d,
                    global int *out)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    int k = get_global_id(0);
    out[k] = occluded(&sc, o[k].xyz, normalize(d[k].xyz), d[k].w, -1);
}
"""


def random_spheres(rng, n, radius_range=(0.05, 1.5)):
    return np.column_stack([rng.uniform(-10, 10, (n, 3)), rng.uniform(*radius_range, n)]).astype(np.float32)


def triangle_soup(rng, n, size=1.5):
    centres = rng.uniform(-10, 10, (n, 1, 3))
    return (centres + rng.normal(scale=size, size=(n, 3, 3))).astype(np.float32)


def scene_of(spheres=(), triangles=()):
    """A scene of spheres and one mesh holding the given triangles ((T, 3, 3) corners)."""
    b = SceneBuilder()
    m = b.material(diffuse(0.5))
    for s in spheres:
        b.add_sphere(s[:3], s[3], m)
    if len(triangles):
        t = np.asarray(triangles, np.float32)
        b.add_mesh(Mesh("soup", t.reshape(-1, 3), np.arange(3 * len(t), dtype=np.int32).reshape(-1, 3), None, m))
    return b.build("test")


@pytest.fixture(params=["default", "ploc"])
def top_work(request, monkeypatch):
    """Each build test twice: as built (a scene of up to HOST_MAX primitives on the host, whose
    tree is the device's: test_a_tree_built_on_the_host_is_the_devices; a larger one by the
    device, split whole by the binned SAH, PLOC competing only for the top), and by the device
    with PLOC clustering down to two clusters. build_bvh is the device's builder either way."""
    if request.param == "ploc":
        monkeypatch.setattr(bvh_cache, "HOST_MAX", 0)
        monkeypatch.setattr(bvh_module, "TOP_CLUSTERS", 0)
    return request.param


def slots(nodes):
    """Every child slot of the 4-wide nodes: (node, lo (3), hi (3), index, count), unused ones too."""
    lo = np.stack([nodes[f"lo_{a}"] for a in "xyz"], axis=-1)        # (nodes, 4, 3)
    hi = np.stack([nodes[f"hi_{a}"] for a in "xyz"], axis=-1)
    node = np.repeat(np.arange(len(nodes)), 4)
    return node, lo.reshape(-1, 3), hi.reshape(-1, 3), nodes["index"].reshape(-1), nodes["count"].reshape(-1)


def leaf_ranges(nodes):
    _, lo, hi, index, count = slots(nodes)
    leaf = count != 0
    return [dict(lo=l, hi=h, index=i, count=c) for l, h, i, c in zip(lo[leaf], hi[leaf], index[leaf], count[leaf])]


@pytest.mark.parametrize("n_spheres,n_triangles", [(1, 0), (0, 1), (2, 0), (3, 4), (7, 0), (100, 100), (0, 3000), (2000, 3000)])
def test_every_primitive_in_one_leaf_and_inside_its_boxes(n_spheres, n_triangles, top_work):
    rng = np.random.default_rng(n_spheres + n_triangles)
    c = compile_scene(scene_of(random_spheres(rng, n_spheres), triangle_soup(rng, n_triangles)))
    n = n_spheres + n_triangles
    assert sorted(c.bvh.order.tolist()) == list(range(n))
    covered = {"s": [], "t": []}
    for leaf in leaf_ranges(c.bvh.nodes):
        kind, count = ("s", leaf["count"]) if leaf["count"] > 0 else ("t", -leaf["count"])
        idx = np.arange(leaf["index"], leaf["index"] + count)
        covered[kind].extend(idx.tolist())
        if kind == "s":
            s = c.spheres[idx]
            lo, hi = s[:, :3] - s[:, 3:], s[:, :3] + s[:, 3:]
        else:
            corners = np.stack([c.triangles[f][idx, :3] for f in ("v0", "v1", "v2")], axis=1)
            lo, hi = corners.min(axis=1), corners.max(axis=1)
        assert np.all(lo >= leaf["lo"]) and np.all(hi <= leaf["hi"])
    assert sorted(covered["s"]) == list(range(n_spheres))
    assert sorted(covered["t"]) == list(range(n_triangles))
    assert c.bvh.depth <= MAX_DEPTH


def test_children_boxes_nest(top_work):
    """An inner slot's box holds every used slot of the node it points to; every node but the root
    is pointed to once; unused slots lie at +inf."""
    rng = np.random.default_rng(3)
    nodes = compile_scene(scene_of(random_spheres(rng, 1500), triangle_soup(rng, 1500))).bvh.nodes
    node, lo, hi, index, count = slots(nodes)
    unused = (count == 0) & (index == -1)
    assert np.all(lo[unused] == np.inf) and np.all(hi[unused] == np.inf)
    inner = (count == 0) & (index >= 0)
    assert sorted(index[inner].tolist()) == list(range(1, len(nodes)))
    for k in np.flatnonzero(inner):
        used = (node == index[k]) & ~unused
        assert 2 <= used.sum() <= 4
        assert np.all(lo[used] >= lo[k]) and np.all(hi[used] <= hi[k])


@pytest.mark.parametrize("n_spheres,n_triangles", [(1, 1), (0, 2), (32, 0), (30, 70), (0, 1000), (4096, 4096),
                                                   (0, bvh_cache.MIN_PRIMITIVES - 1)])
@pytest.mark.parametrize("ploc_only", [False, True])
def test_a_tree_built_on_the_host_is_the_devices(backend, monkeypatch, n_spheres, n_triangles, ploc_only):
    """The host's tree is, byte for byte, the one the device's builder makes of the same boxes:
    the same Morton order, PLOC's passes, binned split and collapse, and the same choice of top
    (for 30 spheres and 70 triangles PLOC's top for the triangles, the split's for the spheres).
    With PLOC down to two clusters too."""
    if ploc_only:
        monkeypatch.setattr(bvh_module, "TOP_CLUSTERS", 0)
    rng = np.random.default_rng(n_spheres + 7 * n_triangles)
    lo = rng.uniform(-10, 10, (n_spheres + n_triangles, 3)).astype(np.float32)
    hi = lo + rng.uniform(0.01, 0.6, lo.shape).astype(np.float32)
    host, device = build_on_host(lo, hi, n_spheres), build_bvh(lo, hi, n_spheres, backend.queue)
    assert host.nodes.tobytes() == device.nodes.tobytes() and np.array_equal(host.order, device.order)
    assert (host.depth, host.cost) == (device.depth, device.cost)


def test_a_small_tree_needs_no_device(monkeypatch):
    """A scene of at most HOST_MAX primitives is compiled with its tree and no device:
    no builder is made (its program's build and, on PoCL, its kernels' compiles were most of a
    small scene's cold start)."""
    def no_builder(queue=None):
        raise AssertionError("a builder was asked for")
    monkeypatch.setattr(bvh_module, "builder_for", no_builder)
    rng = np.random.default_rng(2)
    c = compiled_module.compile_before_devices(scene_of(random_spheres(rng, 300), triangle_soup(rng, 700)))
    assert c.tree_ended is not None and sorted(c.bvh.order.tolist()) == list(range(1000))


def test_a_devices_opening_forgets_the_last_scenes_tree(monkeypatch):
    """A scene whose tree needed no device leaves no word for the next opening of devices, whose
    own scene is yet to be compiled (api.DevicesOpening)."""
    from pathtrace import api
    monkeypatch.setattr(api, "open_devices", lambda device: [])
    compiled_module.compile_before_devices(scene_of(random_spheres(np.random.default_rng(1), 10), []))
    assert not builder_module.builder_wanted()
    api.DevicesOpening("cpu").result()
    assert builder_module.builder_wanted()


def test_a_scene_of_large_mesh_files_has_the_opening_compile_the_builders_kernels_ahead(backend, tmp_path,
                                                                                         monkeypatch):
    """A reader that names LARGE_SCENE_BYTES of mesh files or more says, before its compile can,
    that a tree is likely (tree_likely): a devices' opening that ends after that has its builder
    compile its kernels ahead, beside the rest of the reading. A scene of fewer bytes says
    nothing, and a new opening forgets the word."""
    from pathtrace import api
    from pathtrace.bench.scenes import write_obj_meshes
    from pathtrace.scene import load_scene, meshes
    one, two = tmp_path / "one", tmp_path / "two"
    one.mkdir(), two.mkdir()
    small, large = write_obj_meshes(one, count=1), write_obj_meshes(two, count=2)
    monkeypatch.setattr(meshes, "LARGE_SCENE_BYTES", (one / "o0000.obj").stat().st_size + 1)
    monkeypatch.setattr(builder_module, "_builders", {})
    asked = []
    monkeypatch.setattr(builder_module.Builder, "compile_ahead", lambda self: asked.append(self))
    read = threading.Event()
    monkeypatch.setattr(api, "open_devices", lambda device: [backend] if read.wait(30) else [])

    def opening_ended():
        """Joins the devices' opening threads: their builders are made and asked to compile ahead."""
        for thread in threading.enumerate():
            if thread.name.startswith("open-devices"):
                thread.join(30)

    def opened_after(path):
        api.DevicesOpening("cpu")
        load_scene(str(path))
        likely = builder_module.tree_likely()
        read.set()
        opening_ended()
        read.clear()
        return likely
    assert not opened_after(small) and list(builder_module._builders) == [backend.queue] and asked == []
    monkeypatch.setattr(builder_module, "_builders", {})
    assert opened_after(large) and asked == [builder_module._builders[backend.queue]]
    api.DevicesOpening("cpu")
    assert not builder_module.tree_likely()
    read.set()
    opening_ended()


def test_identical_boxes_still_split():
    lo = np.tile([1.0, 2.0, 3.0], (1000, 1)).astype(np.float32)
    bvh = build_bvh(lo, lo + 0.5)
    assert bvh.nodes["count"].max() <= 4 and bvh.depth < 20


def nearest_rays(rng, rays, aim_at):
    """Origins in a cube around the primitives and directions (float4 each), half of them aimed
    at a primitive."""
    o = np.column_stack([rng.uniform(-15, 15, (rays, 3)), np.zeros(rays)]).astype(np.float32)
    d = rng.normal(size=(rays, 3))
    targets = aim_at[rng.integers(0, len(aim_at), rays // 2)]
    d[: rays // 2] = targets - o[: rays // 2, :3]
    return o, np.column_stack([d, np.zeros(rays)]).astype(np.float32)


def nearest(kernels, compiled, o, d):
    """The nearest hits of rays o, d (float4 each): through the BVH (t, primitive) and by brute
    force over all primitives (t, primitive)."""
    rays = len(o)
    out = [np.zeros(rays, np.float32), np.zeros(rays, np.int32), np.zeros(rays, np.float32), np.zeros(rays, np.int32)]
    kernels(SOURCE, layout_features(compiled))("nearest", rays, *scene_arrays(compiled),
                                               np.int32(compiled.num_spheres),
                                               np.int32(compiled.num_triangles), o, d, *out)
    return out


@pytest.mark.parametrize("case", ["spheres", "soup", "mixed", "lone", "coincident", "one-point", "degenerate-neighbours"])
def test_nearest_hit_matches_brute_force(kernels, case, top_work):
    rng = np.random.default_rng(len(case))
    spheres, tris = np.zeros((0, 4), np.float32), np.zeros((0, 3, 3), np.float32)
    if case == "spheres":
        spheres = random_spheres(rng, 5000)
    elif case == "soup":
        tris = triangle_soup(rng, 5000)
    elif case == "mixed":
        spheres, tris = random_spheres(rng, 2000), triangle_soup(rng, 3000)
    elif case == "lone":            # a few spheres, which rays test outside the tree (LONE_SPHERES)
        spheres, tris = random_spheres(rng, LONE_MAX, (1.0, 3.0)), triangle_soup(rng, 3000)
    elif case == "coincident":      # every triangle three times, and 100 copies of one
        base = triangle_soup(rng, 500)
        tris = np.concatenate([base, base, base, np.repeat(base[:1], 100, axis=0)])
    elif case == "one-point":       # all primitives at (or around) one point
        spheres = np.tile([1.0, 1.0, 1.0, 0.5], (300, 1)).astype(np.float32)
        tris = np.repeat(triangle_soup(rng, 1, size=0.5) * 0 + np.array([[1, 1, 1], [2, 1, 1], [1, 2, 1]], np.float32),
                         300, axis=0)
    else:                           # thin slivers between ordinary triangles
        tris = triangle_soup(rng, 2000)
        sliver = tris[:500].copy()
        sliver[:, 2] = sliver[:, 0] + 1e-4 * (sliver[:, 1] - sliver[:, 0])
        tris = np.concatenate([tris, sliver])
    c = compile_scene(scene_of(spheres, tris))
    assert c.lone_spheres == (LONE_MAX if case == "lone" else 0)
    aim_at = np.concatenate([spheres[:, :3], tris.mean(axis=1)])
    t_bvh, i_bvh, t_all, i_all = nearest(kernels, c, *nearest_rays(rng, 20000, aim_at))
    np.testing.assert_array_equal(t_bvh, t_all)
    # different primitives only where two are met at exactly the same t
    assert np.all((i_bvh == i_all) | (t_bvh == t_all))
    assert np.mean(np.isfinite(t_all)) > 0.3
    if len(spheres):
        assert np.mean((i_all >= 0) & (i_all < len(spheres))) > 0.02     # the spheres are met too


def test_nearest_hit_far_from_the_origin(kernels):
    """Triangles of a hundredth of a unit 1000 units from the world's origin, met by rays that
    start among them and aim at their corners, through the corners of their boxes: the fused box
    test (kernels/bvh.cl: intersect_boxes) rounds -o * inv_d at the scale of 1000, and still
    loses no hit to brute force."""
    rng = np.random.default_rng(13)
    offset = np.array([1000.0, -700.0, 400.0])
    centres = offset + rng.uniform(-0.05, 0.05, (3000, 1, 3))
    tris = (centres + rng.normal(scale=0.01, size=(3000, 3, 3))).astype(np.float32)
    c = compile_scene(scene_of((), tris))
    rays = 20000
    o = np.zeros((rays, 4), np.float32)
    o[:, :3] = offset + rng.uniform(-0.08, 0.08, (rays, 3))
    d = np.zeros((rays, 4), np.float32)
    d[:, :3] = tris[rng.integers(0, len(tris), rays), rng.integers(0, 3, rays)] - o[:, :3]
    t_bvh, i_bvh, t_all, i_all = nearest(kernels, c, o, d)
    np.testing.assert_array_equal(t_bvh, t_all)
    assert np.all((i_bvh == i_all) | (t_bvh == t_all))
    assert np.mean(np.isfinite(t_all)) > 0.9


@pytest.mark.parametrize("case", ["spheres", "mixed", "lone"])
def test_shadow_rays_match_brute_force(kernels, case, top_work):
    """occluded(), the any-hit walk of shadow rays, says whether anything lies before t_max
    exactly where the brute-force nearest hit does (rays whose nearest hit is within a part in
    10^5 of t_max are left out, where float rounding decides)."""
    rng = np.random.default_rng(21)
    spheres = random_spheres(rng, LONE_MAX, (1.0, 3.0)) if case == "lone" \
        else random_spheres(rng, 2000 if case == "mixed" else 5000)
    tris = triangle_soup(rng, 3000) if case != "spheres" else np.zeros((0, 3, 3), np.float32)
    c = compile_scene(scene_of(spheres, tris))
    aim_at = np.concatenate([spheres[:, :3], tris.mean(axis=1)])
    rays = 20000
    o, d = nearest_rays(rng, rays, aim_at)
    t_all = nearest(kernels, c, o, d)[2]
    d[:, 3] = rng.uniform(0.0, 30.0, rays)       # t_max
    out = np.zeros(rays, np.int32)
    kernels(SOURCE, layout_features(c))("blocked", rays, *scene_arrays(c), np.int32(c.num_spheres), o, d, out)
    clear = np.abs(t_all - d[:, 3]) > 1e-5 * d[:, 3]
    np.testing.assert_array_equal(out[clear] != 0, (t_all < d[:, 3])[clear])
    assert 0.2 < np.mean(out) < 0.8


def window_nearest(boxes, radius):
    """kernels/build/ploc.cl's rule in NumPy: the smallest union area within `radius` places, ties
    to the smaller index distance, then by whether (lower index / k) is odd."""
    lo, hi = boxes[:, 0, :3], boxes[:, 1, :3]
    out = np.empty(len(boxes), np.int64)
    for i in range(len(boxes)):
        best = None
        for k in range(1, radius + 1):
            for j in (i + k, i - k):
                if 0 <= j < len(boxes):
                    e = np.minimum(np.maximum(hi[i], hi[j]) - np.minimum(lo[i], lo[j]), np.finfo(np.float32).max)
                    area = np.float32(e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
                    key = (area, k, (min(i, j) // k) & 1)
                    if best is None or key < best[0]:
                        best = (key, j)
        out[i] = best[1]
    return out


@pytest.mark.parametrize("case", ["random", "identical", "grid"])
def test_ploc_nearest_neighbours_follow_the_pair_order(backend, case):
    rng = np.random.default_rng(7)
    n = 300
    if case == "random":
        lo = rng.uniform(0, 10, (n, 3))
        hi = lo + rng.uniform(0, 1, (n, 3))
    elif case == "identical":
        lo, hi = np.zeros((n, 3)), np.ones((n, 3))
    else:                  # many exact ties of area
        lo = np.column_stack([np.arange(n) % 4, np.arange(n) // 4 % 4, np.zeros(n)])
        hi = lo + 1
    boxes = np.zeros((n, 2, 4), np.float32)
    boxes[:, 0, :3], boxes[:, 1, :3] = lo, hi
    b = builder_for(backend.queue)
    box, nearest = b.buffer(boxes.nbytes), b.buffer(4 * n)
    b.write(box, boxes)
    b.launch("find_nearest", n, box, np.int32(n), np.int32(RADIUS), nearest)
    got = b.read(nearest, n, np.int32)
    np.testing.assert_array_equal(got, window_nearest(boxes, RADIUS))
    if case == "identical":   # they pair up, so a pass halves them
        np.testing.assert_array_equal(got, np.arange(n) ^ 1)


def test_deep_chains_are_cut_at_max_depth():
    """Boxes at x = 2^k: the cluster of boxes 0..k is always nearest to box k + 1, so PLOC makes a
    chain 60 deep; below MAX_DEPTH it becomes one leaf, and every primitive is still in exactly
    one leaf."""
    lo = np.column_stack([2.0 ** np.arange(60), np.zeros(60), np.zeros(60)]).astype(np.float32)
    bvh = build_bvh(lo, lo + 1)
    assert bvh.depth == MAX_DEPTH
    counts = bvh.nodes["count"]
    assert counts[counts != 0].sum() == 60
    assert sorted(bvh.order.tolist()) == list(range(60))


def test_the_build_is_deterministic_and_reports_progress(backend):
    rng = np.random.default_rng(11)
    tris = triangle_soup(rng, 20000)
    lo, hi = tris.min(axis=1), tris.max(axis=1)
    seen = []
    a = build_bvh(lo, hi, 0, backend.queue, seen.append)
    b = build_bvh(lo, hi, 0, backend.queue)
    assert a.nodes.tobytes() == b.nodes.tobytes() and np.array_equal(a.order, b.order)
    assert np.all(np.diff(seen) >= 0) and seen[-1] == pytest.approx(1.0)



@pytest.mark.parametrize("n,spheres", [(9, 3), (1000, 400), (70000, 1000)])
def test_the_build_reads_nothing_it_has_not_written(backend, monkeypatch, n, spheres):
    """A GPU's fresh buffers hold whatever was there: with every scratch buffer of the builder
    filled with random bytes first, the tree is the one built in PoCL's zeroed buffers, byte
    for byte (Oclgrind had reported values it took for uninitialised in merge_clusters)."""
    import pyopencl as cl
    rng = np.random.default_rng(n)
    c = rng.uniform(-10, 10, (n, 3)).astype(np.float32)
    r = rng.uniform(0.01, 0.5, (n, 1)).astype(np.float32)
    clean = build_bvh(c - r, c + r, spheres, backend.queue)
    buffer = builder_module.Builder.buffer

    def garbage(self, nbytes):
        buf = buffer(self, nbytes)
        cl.enqueue_copy(self.queue, buf, rng.integers(0, 256, max(int(nbytes), 4), dtype=np.uint8))
        return buf
    monkeypatch.setattr(builder_module.Builder, "buffer", garbage)
    dirty = build_bvh(c - r, c + r, spheres, backend.queue)
    assert clean.nodes.tobytes() == dirty.nodes.tobytes() and np.array_equal(clean.order, dirty.order)

def test_sah_cost_is_near_a_full_sweep_build(top_work):
    """The SAH cost against a top-down full-sweep SAH build (every split position on every axis, the
    classic high-quality reference) of the same 2000 spheres: within 10 %, with PLOC alone too."""
    rng = np.random.default_rng(5)
    s = random_spheres(rng, 2000, (0.05, 0.4))
    lo, hi = s[:, :3] - s[:, 3:], s[:, :3] + s[:, 3:]
    assert build_bvh(lo, hi).cost < 1.1 * full_sweep_sah(lo.astype(np.float64), hi.astype(np.float64))


def full_sweep_sah(lo, hi):
    """The SAH cost (as pathtrace.compiler.bvh.BVH.cost counts it) of a top-down full-sweep build with leaves of at
    most MAX_LEAF_SIZE, recursive and slow: a reference for small inputs only."""
    def area(l, h):
        d = h - l
        return 2 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0])

    def build(idx):
        box_a = area(lo[idx].min(axis=0), hi[idx].max(axis=0))
        n = len(idx)
        best = (np.inf, None)
        if n > 1:
            cen = (lo[idx] + hi[idx]) / 2
            for axis in range(3):
                order = idx[np.argsort(cen[:, axis], kind="stable")]
                l_lo, l_hi = np.minimum.accumulate(lo[order]), np.maximum.accumulate(hi[order])
                r_lo = np.minimum.accumulate(lo[order][::-1])[::-1]
                r_hi = np.maximum.accumulate(hi[order][::-1])[::-1]
                for k in range(1, n):
                    c = TRAVERSAL_COST + (k * area(l_lo[k - 1], l_hi[k - 1])
                                          + (n - k) * area(r_lo[k], r_hi[k])) / box_a
                    if c < best[0]:
                        best = (c, (order[:k], order[k:]))
        if n <= MAX_LEAF_SIZE and n <= best[0]:
            return n * box_a               # a leaf: its primitives, weighted by its area
        left, right = best[1]
        return TRAVERSAL_COST * box_a + build(left) + build(right)

    idx = np.arange(len(lo))
    root = area(lo.min(axis=0), hi.max(axis=0))
    return build(idx) / root


def most_pushes(nodes) -> int:
    """The most entries kernels/bvh.cl's stack can hold on this tree: along each path from the
    root, the inner children that a node pushes besides the one it visits next."""
    def walk(node, held):
        inner = [int(i) for i, c in zip(nodes["index"][node], nodes["count"][node]) if c == 0 and i >= 0]
        if not inner:
            return held
        pushed = held + len(inner) - 1
        return max(walk(child, pushed) for child in inner)
    return walk(0, 0)


@pytest.mark.parametrize("build", ["chain", "random", "ploc"])
def test_the_kernels_stack_holds_every_tree(build, monkeypatch):
    """kernels/bvh.cl's traversal stack holds what traversal can push on the deepest tree
    app/compiler/bvh.py makes (a chain cut at MAX_DEPTH) and on random ones: every scene's
    program has it, so that the program need not wait for the tree."""
    size = int(re.search(r"#define BVH_STACK_SIZE (\d+)", (resource_dir("kernels") / "bvh.cl").read_text()).group(1))
    rng = np.random.default_rng(5)
    if build == "chain":
        lo = np.column_stack([2.0 ** np.arange(60), np.zeros(60), np.zeros(60)]).astype(np.float32)
        hi = lo + 1
    else:
        if build == "ploc":
            monkeypatch.setattr(bvh_module, "TOP_CLUSTERS", 0)
        lo = rng.uniform(-10, 10, (20000, 3)).astype(np.float32)
        hi = lo + rng.uniform(0.01, 1, (20000, 3)).astype(np.float32)
    bvh = build_bvh(lo, hi)
    assert most_pushes(bvh.nodes) <= size
    # traversal pushes at most three children of each 4-wide level, which has at most
    # ceil(MAX_DEPTH / 2) + 1 levels
    assert size == 3 * ((MAX_DEPTH + 1) // 2) + 3


FLAT_MIXED = """
[camera]
eye = [0, 1, 4]
look_at = [0, 0.5, 0]
[environment]
color = 0.8
[[spheres]]
center = [-0.6, 0.5, 0]
radius = 0.5
material = { type = "diffuse", rho_d = 0.7 }
[[spheres]]
center = [0.7, 1.6, -0.5]
radius = 0.3
material = { type = "emitter", Le = 4 }
[[meshes]]
vertices = [[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2], [0.2, 0, -1], [1.2, 1, -1], [0.2, 1.2, -1]]
faces = [[0, 2, 1], [0, 3, 2], [4, 5, 6]]
material = { type = "diffuse", rho_d = 0.5 }
"""


@pytest.mark.specialised
@pytest.mark.parametrize("scene", ["simple", "mixed"])
@pytest.mark.parametrize("nee", [False, True])
def test_a_flat_scene_renders_as_its_tree_does(backend, monkeypatch, tmp_path, scene, nee):
    """A scene of at most FLAT_MAX primitives is built without traversal (app/device/features.py): its
    rays find the hits its BVH gives, so the same samples make the same image."""
    from dataclasses import replace

    from pathtrace.compiler.compiled import CompiledScene
    from pathtrace.rendering.renderer import Renderer
    from pathtrace.scene import load_scene
    if scene == "mixed":
        (tmp_path / "mixed.toml").write_text(FLAT_MIXED)
        scene = str(tmp_path / "mixed.toml")
    loaded = load_scene(scene).with_settings(nee=nee)

    def render():
        r = Renderer(backend, loaded, 48, 32)
        r.add_samples(4)
        return r.compiled.features(r.settings, r.camera), r.mean()
    features, flat = render()
    assert features.flat and sum(features.flat) <= 8
    tree_features = CompiledScene.features
    monkeypatch.setattr(CompiledScene, "features", lambda self, settings, camera: replace(tree_features(self, settings, camera), flat=()))
    features, tree = render()
    assert not features.flat and flat.mean() > 0
    np.testing.assert_allclose(flat, tree, rtol=1e-4, atol=1e-6)


@pytest.mark.specialised
def test_a_scene_of_triangles_only_renders_without_the_sphere_code(backend, monkeypatch):
    """A scene without spheres compiles its traversal without the sphere test (NO_SPHERES,
    app/device/features.py), which a scene does not pay for where it has none: the same samples make the
    same image as the program with it. The Cornell box's quads in a tree of their own, whose
    program without the sphere test other tests build too."""
    from dataclasses import replace

    from pathtrace.compiler.compiled import CompiledScene
    from pathtrace.rendering.renderer import Renderer
    from pathtrace.scene import load_scene
    loaded = load_scene("cornell-box")

    def render():
        r = Renderer(backend, loaded, 48, 32)
        r.add_samples(4)
        return r.compiled.features(r.settings, r.camera), r.mean()
    features, without = render()
    assert not features.spheres and "NO_SPHERES" in features.defines() and not features.flat
    specialised = CompiledScene.features
    monkeypatch.setattr(CompiledScene, "features",
                        lambda self, settings, camera: replace(specialised(self, settings, camera), spheres=True))
    features, with_spheres = render()
    assert "NO_SPHERES" not in features.defines() and without.mean() > 0
    np.testing.assert_allclose(without, with_spheres, rtol=1e-5, atol=1e-7)
    assert CompiledScene(load_scene("simple")).features(loaded.settings, loaded.camera).spheres


@pytest.mark.specialised
def test_a_few_spheres_beside_triangles_stay_out_of_the_tree(backend, monkeypatch):
    """teapot-sky, a teapot on a ground quad with one sphere: the sphere is outside the tree
    (LONE_SPHERES), whose leaves hold triangles only, and the same samples make the same image as
    with the sphere in the tree."""
    import pathtrace.compiler.compiled as compiled_module
    from pathtrace.rendering.renderer import Renderer
    from pathtrace.scene import load_scene
    loaded = load_scene("teapot-sky")

    def render():
        r = Renderer(backend, loaded, 48, 32)
        r.add_samples(4)
        return r.compiled, r.compiled.features(r.settings, r.camera), r.mean()
    compiled, features, lone = render()
    assert compiled.lone_spheres == compiled.num_spheres == 1 and "LONE_SPHERES=1" in features.defines()
    assert np.all(compiled.bvh.nodes["count"] <= 0)
    monkeypatch.setattr(compiled_module, "LONE_MAX", 0)
    compiled, features, in_tree = render()
    assert not compiled.lone_spheres and np.any(compiled.bvh.nodes["count"] > 0)
    assert not any(d.startswith("LONE_SPHERES") for d in features.defines())
    np.testing.assert_allclose(lone, in_tree, rtol=1e-5, atol=1e-7)
    assert lone.mean() > 0


def test_the_build_kernels_compiled_ahead_serve_every_launch_of_a_build(backend, tmp_path):
    """Builder.launch_ahead (PoCL) compiles each build kernel once, for grids of WHOLE_GRID
    work-items, and a build after it in the process, whose launches are all smaller, compiles
    nothing more: a fresh PoCL cache then holds one compile of each kernel, none of them the
    `smallgrid` one that the same build alone compiles (tests/test_cli.py: warm_builder)."""
    if not keeps_own_cache(backend.device.device):
        pytest.skip("only PoCL compiles a kernel at its first launch; other drivers, at the build")
    code = ("import numpy as np; from pathtrace.compiler.builder import builder_for; "
            "from pathtrace.compiler.bvh import build_bvh; "
            "from pathtrace.device.opencl import choose_device; "
            "q = choose_device('cpu', log=lambda line: None).queue; builder_for(q).launch_ahead(); "
            "lo = np.random.default_rng(1).random((3000, 3), np.float32); "
            "build_bvh(lo, lo + np.float32(0.01), num_spheres=0, queue=q)")
    env = {**os.environ, "POCL_CACHE_DIR": str(tmp_path / "pocl"), "XDG_CACHE_HOME": str(tmp_path / "xdg")}
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True, capture_output=True)
    compiled = [(k.name, v.name) for k in (tmp_path / "pocl").glob("*/*/*") if k.is_dir() for v in k.iterdir()]
    names = {m for f in (ROOT / "kernels" / "build").glob("*.cl")
             for m in re.findall(r"^kernel void (\w+)", f.read_text(), re.M)}
    assert len(names) >= 10
    assert sorted(name for name, _ in compiled) == sorted(names), compiled
    assert not any("smallgrid" in variant for _, variant in compiled), compiled


def test_an_expected_tree_has_every_builder_compile_ahead(backend, monkeypatch):
    """expect_tree: the builders made before it and after it compile their kernels ahead."""
    asked = []
    monkeypatch.setattr(builder_module, "_builders", {})
    monkeypatch.setattr(builder_module, "_tree_expected", False)
    monkeypatch.setattr(builder_module.Builder, "compile_ahead", lambda self: asked.append(self))
    first = builder_for(backend.queue)
    assert asked == []
    builder_module.expect_tree()
    assert asked == [first]
    second = builder_for(cl.CommandQueue(backend.context))
    assert second is not first and asked[-1] is second


def test_a_scene_compiled_before_its_devices_expects_its_tree_where_the_cache_lacks_it(monkeypatch):
    """compile_before_devices says a tree will be built (expect_tree) for a scene of more than
    HOST_MAX primitives that the BVH cache does not hold (it is off in the tests), not for one of
    HOST_MAX, whose tree the host builds, nor a lone sphere; for those it says that the devices
    need no builder in advance (no_device_tree, builder_wanted)."""
    expected = []
    monkeypatch.setattr(compiled_module, "expect_tree", lambda: expected.append(True))
    for flag in ("_tree_without_device", "_tree_expected"):
        monkeypatch.setattr(builder_module, flag, False)
    monkeypatch.setattr(builder_module, "_builders", {})
    rng = np.random.default_rng(4)
    compiled_module.compile_before_devices(scene_of(random_spheres(rng, bvh_cache.HOST_MAX + 1), []))
    assert expected == [True] and builder_module.builder_wanted()
    compiled_module.compile_before_devices(scene_of(random_spheres(rng, bvh_cache.HOST_MAX), []))
    compiled_module.compile_before_devices(scene_of([[0, 0, 0, 1]], []))
    assert expected == [True]
    assert not builder_module.builder_wanted()      # the devices' opening makes no builder
    builder_module.expect_tree()
    assert builder_module.builder_wanted()


def test_the_wait_for_the_kernels_ahead_ends_where_nothing_is_compiled_ahead(backend, monkeypatch):
    """await_kernels_ahead returns at once where no tree is expected, and where one is on a device
    that compiles its kernels at their build (not PoCL), whose builder launches nothing ahead."""
    import pathtrace.device.opencl as opencl
    monkeypatch.setattr(builder_module, "_builders", {})
    monkeypatch.setattr(builder_module, "_tree_expected", False)
    builder_module.await_kernels_ahead(backend.queue)
    assert not builder_module._builders
    monkeypatch.setattr(builder_module, "_tree_expected", True)
    monkeypatch.setattr(opencl, "keeps_own_cache", lambda device: False)
    launched = []
    monkeypatch.setattr(builder_module.Builder, "launch_ahead", lambda self: launched.append(self))
    builder_module.await_kernels_ahead(backend.queue)
    assert builder_for(backend.queue).ahead_done.is_set() and launched == []


def test_a_built_tree_ends_the_expectation(backend, monkeypatch):
    """Once the expected tree is built, builders made later compile nothing ahead, and a
    program's build waits for nothing (await_kernels_ahead)."""
    monkeypatch.setattr(builder_module, "_builders", {})
    builder_module.expect_tree()
    lo = np.random.default_rng(3).random((100, 3), np.float32)
    build_bvh(lo, lo + np.float32(0.01), queue=backend.queue)
    asked = []
    monkeypatch.setattr(builder_module.Builder, "compile_ahead", lambda self: asked.append(self))
    builder_for(cl.CommandQueue(backend.context))
    assert not builder_module._tree_expected and asked == []
