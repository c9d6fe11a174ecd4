"""A bounding volume hierarchy over spheres and triangles together, built on an OpenCL device and
laid out as the 4-wide BVHNode array that kernels/bvh.cl walks. In three steps:

1. Bottom-up by PLOC, parallel locally-ordered clustering (Meister and Bittner, IEEE TVCG 2018;
   kernels/build/ploc.cl). The primitives are sorted along a 63-bit Morton curve of their
   centroids (kernels/build/morton.cl); each pass, every cluster finds the cluster within RADIUS
   places of it in that order whose union with it has the smallest surface area, and mutual
   nearest neighbours merge into one cluster in the place of the first. Passes repeat until the
   clusters are few enough for step 2.
2. Over the remaining clusters, two candidate tops: PLOC's passes continued, and a top-down split
   by the binned surface area heuristic (Wald, "On fast Construction of SAH-based Bounding Volume
   Hierarchies", 2007) here in NumPy; the one of smaller SAH cost is kept. PLOC's greedy merges
   make poorer trees than the binned split on evenly spread primitives, the binned split a
   poorer top on the teapot over its floor. PLOC stops at min(N, TOP_CLUSTERS) clusters: scenes
   of up to 65536 primitives are split whole, larger ones above 65536 clusters. The split's time
   grows with its clusters, not with N, and its gain is largest where PLOC's clusters straddle
   empty space (docs/notes/performance-2026-11.md, 2026-11-22 and 2026-11-25: the binned split).
3. Collapsed by the SAH (as pbrt-v4's builder decides): a subtree of at most MAX_LEAF_SIZE
   primitives becomes one leaf where that is cheaper than its split; then every other level of
   the binary tree is folded into its parent, giving 4-wide nodes, laid out depth-first
   (kernels/build/collapse.cl). Testing four boxes with float4 operations traces faster than a
   binary tree on GPUs and on PoCL alike (docs/performance.md, The BVH).

Leaves hold one kind of primitive (kernels/types.h): spheres and triangles are built apart and
their two trees joined at the root. Nodes are made in batches (a PLOC pass, a level of the top
split) whose members depend only on earlier batches below them, so step 3 sweeps the tree with
one launch per batch. The host only sorts the Morton codes, sums each pass's per-group counts and
splits the top; the tree stays on the device until its nodes are read back. A small scene's tree
is built by the same steps on the host (app/compiler/host_bvh.py: build_tree takes either tree).
"""

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pyopencl as cl

from pathtrace.compiler.builder import GROUP, TRAVERSAL_COST, Builder, builder_for, tree_built
from pathtrace.device.types import BVH_NODE

RADIUS = 8                  # PLOC's search radius: 8 and 16 give trees of the same SAH cost here
TOP_CLUSTERS = 65536        # PLOC stops at min(N, TOP_CLUSTERS) clusters (see step 2)
MORTON_BITS = 21            # per axis: 63 bits in all
MAX_BINS = 16


@dataclass
class BVH:
    nodes: np.ndarray       # BVH_NODE (4-wide) array; node 0 is the root
    order: np.ndarray       # primitive i in the BVH's order is primitive order[i] of the input
    depth: int              # of the binary tree's deepest leaf, the root's children at depth 1
    cost: float             # the binary tree's SAH cost relative to its root box: TRAVERSAL_COST
                            # per inner node visited, one per primitive tested (MacDonald and
                            # Booth 1990)


def primitive_boxes(spheres: np.ndarray, triangles: np.ndarray):
    """Boxes of spheres ((S, 4) centre and radius) followed by triangles ((T, 3, 3) corners), in
    float32 as the kernels see them."""
    spheres = np.asarray(spheres, np.float32).reshape(-1, 4)
    triangles = np.asarray(triangles, np.float32).reshape(-1, 3, 3)
    # the corners compared pairwise: 7x faster than a reduction over the short axis
    t0, t1, t2 = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    lo = np.concatenate([spheres[:, :3] - spheres[:, 3:], np.minimum(np.minimum(t0, t1), t2)])
    hi = np.concatenate([spheres[:, :3] + spheres[:, 3:], np.maximum(np.maximum(t0, t1), t2)])
    return lo, hi


def column_min(a: np.ndarray) -> np.ndarray:
    """The minimum of each column of an (N, k) array: NumPy reduces a short row axis-0-wise 20x
    slower than a column at a time (26 ms against 1.2 ms for 1M rows of 3)."""
    return np.array([a[:, i].min() for i in range(a.shape[1])], a.dtype)


def column_max(a: np.ndarray) -> np.ndarray:
    return np.array([a[:, i].max() for i in range(a.shape[1])], a.dtype)


def surface_area(lo, hi):
    d = np.maximum(hi - lo, 0)
    return 2 * (d[..., 0] * d[..., 1] + d[..., 1] * d[..., 2] + d[..., 2] * d[..., 0])


class BinaryTree:
    """What the device's tree (_Tree) and the host's (host_bvh.HostTree) number alike:
    primitives are nodes 0..n-1 and each new node gets the next number, made in batches (first
    node, count), each depending only on earlier ones."""

    def __init__(self, n: int):
        self.n = self.made = n
        self.batches: list[tuple[int, int]] = []

    def made_batch(self, count: int) -> np.ndarray:
        self.batches.append((self.made, count))
        self.made += count
        return np.arange(self.made - count, self.made, dtype=np.int32)

    def cut(self, mark):
        """Takes back the nodes made since mark = (made, len(batches))."""
        self.made, batches = mark
        self.batches = self.batches[:batches]


class _Tree(BinaryTree):
    """The binary tree on the device. child: per node (left, right), -1 for primitives; box: per
    node two float4, lo then hi."""

    def __init__(self, builder: Builder, lo: np.ndarray, hi: np.ndarray):
        super().__init__(len(lo))
        self.b = builder
        size = 2 * self.n - 1
        self.child = builder.filled(np.int32(-1), 2 * size)
        self.box = builder.buffer(size * 32)
        boxes = np.zeros((self.n, 2, 4), np.float32)
        boxes[:, 0, :3], boxes[:, 1, :3] = lo, hi
        builder.write(self.box, boxes)

    def add(self, left, right, lo, hi) -> np.ndarray:
        """New nodes made on the host, as one batch; returns their numbers."""
        count = len(left)
        self.b.write(self.child, np.column_stack([left, right]).astype(np.int32), self.made)
        boxes = np.zeros((count, 2, 4), np.float32)
        boxes[:, 0, :3], boxes[:, 1, :3] = lo, hi
        self.b.write(self.box, boxes, self.made)
        return self.made_batch(count)

    def boxes(self, first: int, stop: int) -> np.ndarray:
        return self.b.read(self.box, 2 * (stop - first), np.dtype((np.float32, 4)), 2 * first).reshape(-1, 2, 4)

    def clusters(self, first: int, count: int, c_lo, scale) -> "_Clusters":
        """PLOC's first clusters: the primitives first..first+count-1 in the order of their
        Morton codes (c_lo and scale as kernels/build/morton.cl takes them)."""
        b = self.b
        codes = b.buffer(count * 8)
        b.launch("morton_codes", count, self.box, np.int32(first), np.int32(count), c_lo, scale, codes)
        # not a stable sort, but a deterministic one, and five times faster than NumPy's stable one
        order = np.argsort(b.read(codes, count, np.uint64)).astype(np.int32)
        order_buf = b.buffer(count * 4)
        b.write(order_buf, order)
        clusters = _Clusters(b, count)
        b.launch("first_clusters", count, self.box, order_buf, np.int32(first), np.int32(count),
                 clusters.node, clusters.box)
        return clusters

    def flatten(self, root: int, num_spheres: int) -> BVH:
        return _flatten(self, root, num_spheres)


def build_bvh(lo: np.ndarray, hi: np.ndarray, num_spheres: int = None,
              queue: cl.CommandQueue = None, progress: Callable[[float], None] = None) -> BVH:
    """A BVH over the N primitives given by their boxes lo..hi ((N, 3) each, finite): spheres
    first (num_spheres of them; default: all), then triangles, which leaves keep apart. It is
    built on `queue`'s device (default: builder_for()'s); progress, if given, is called with the
    fraction done after each PLOC pass. Of no primitives (a scene of its environment alone, as
    Mitsuba 3 renders one), a root whose four slots are empty, which no ray enters."""
    lo, hi = np.asarray(lo, np.float32), np.asarray(hi, np.float32)
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise ValueError("build_bvh: primitive boxes must be finite")
    n = len(lo)
    num_spheres = n if num_spheres is None else num_spheres
    if n <= 1:   # a lone primitive: the root's first slot; the others empty (kernels/types.h)
        nodes = np.zeros(1, BVH_NODE)
        for name in ("lo_x", "lo_y", "lo_z", "hi_x", "hi_y", "hi_z"):
            nodes[name] = np.inf
        nodes["index"] = -1
        if n:
            for axis, name in enumerate("xyz"):
                nodes[f"lo_{name}"][0, 0] = np.nextafter(lo[0, axis], np.float32(-np.inf))
                nodes[f"hi_{name}"][0, 0] = np.nextafter(hi[0, axis], np.float32(np.inf))
            nodes["index"][0, 0] = 0
            nodes["count"][0, 0] = 1 if num_spheres else -1
        return BVH(nodes, np.zeros(n, np.int64), 1, float(n))
    bvh = build_tree(_Tree(builder_for(queue), lo, hi), lo, hi, num_spheres, progress)
    tree_built()
    return bvh


def build_tree(tree, lo, hi, num_spheres: int, progress=None) -> BVH:
    """Steps 1 to 3 over N >= 2 primitives (float32 boxes, finite) on `tree`, the device's
    (_Tree) or the host's (pathtrace.compiler.host_bvh.HostTree), which do each step alike."""
    n, merged = len(lo), 0

    def report(count):   # n - 1 merges in all, the join of the kinds' trees included
        nonlocal merged
        merged += count
        if progress:
            progress(merged / (n - 1))

    roots = [_build_kind(tree, lo, hi, first, stop, report)
             for first, stop in ((0, num_spheres), (num_spheres, n)) if stop > first]
    if len(roots) == 2:
        a, b = roots
        box = tree.boxes(a, a + 1)[0], tree.boxes(b, b + 1)[0]
        roots = tree.add([a], [b], [np.minimum(box[0][0], box[1][0])[:3]], [np.maximum(box[0][1], box[1][1])[:3]])
        report(1)
    return tree.flatten(int(roots[0]), num_spheres)


def _build_kind(tree: _Tree, lo, hi, first: int, stop: int, report) -> int:
    """Steps 1 and 2 over the primitives first..stop-1; returns the root."""
    count = stop - first
    if count == 1:
        return first
    cen = lo[first:stop] + hi[first:stop]       # twice the centroids: the order is the same
    c_lo, c_hi = column_min(cen), column_max(cen)
    scale = np.divide((1 << MORTON_BITS) - 1, c_hi - c_lo, out=np.zeros(3, np.float32), where=c_hi > c_lo)
    clusters = tree.clusters(first, count, np.append(c_lo, 0).astype(np.float32),
                             np.append(scale, 0).astype(np.float32))
    clusters.cluster(tree, max(2, min(count, TOP_CLUSTERS)), report)
    node, boxes = clusters.read()
    if clusters.count == 1:
        return int(node[0])
    # two candidate tops over the remaining clusters; the one of smaller SAH cost is kept (the
    # clusters below are the same, so the sum of the new nodes' areas decides)
    levels, split_root = split_top(node, boxes[:, 0, :3], boxes[:, 1, :3], tree.made)
    split_area = sum(surface_area(lo_, hi_).astype(np.float64).sum() for _, _, lo_, hi_ in levels)
    mark = tree.made, len(tree.batches)
    cluster_root = clusters.cluster(tree, 1, report)
    made = tree.boxes(mark[0], tree.made).astype(np.float64)
    if split_area < surface_area(made[:, 0, :3], made[:, 1, :3]).sum():
        tree.cut(mark)
        for level in levels:
            tree.add(*level)
        return split_root
    return cluster_root


class _Clusters:
    """PLOC's clusters on the device: node numbers and boxes, in Morton order, in two buffers that
    passes compact into alternately."""

    def __init__(self, b: Builder, count: int):
        self.b, self.count = b, count
        self.node, self.box = b.buffer(count * 4), b.buffer(count * 32)
        self.node_out, self.box_out = b.buffer(count * 4), b.buffer(count * 32)
        groups = -(-count // GROUP)
        self.nearest, self.prefix = b.buffer(count * 4), b.buffer(count * 8)
        self.group_sum, self.group_start = b.buffer(groups * 8), b.buffer(groups * 8)

    def cluster(self, tree: _Tree, stop: int, report) -> int:
        """Step 1: passes until `stop` clusters are left; returns the last cluster's node."""
        b = self.b
        while self.count > stop:
            count = np.int32(self.count)
            b.launch("find_nearest", self.count, self.box, count, np.int32(RADIUS), self.nearest)
            groups = b.launch("mark_merges", self.count, self.nearest, count, self.prefix, self.group_sum)
            sums = b.read(self.group_sum, groups, np.dtype((np.int32, 2)))
            b.write(self.group_start, np.cumsum(sums, axis=0, dtype=np.int32) - sums)
            b.launch("merge_clusters", self.count, self.nearest, count, self.prefix, self.group_start,
                     np.int32(tree.made), self.node, self.box, self.node_out, self.box_out,
                     tree.child, tree.box)
            merges, self.count = (int(v) for v in sums.sum(axis=0))
            tree.made_batch(merges)
            self.node, self.node_out = self.node_out, self.node
            self.box, self.box_out = self.box_out, self.box
            report(merges)
        return tree.made - 1

    def read(self):
        """The clusters' nodes and boxes ((count, 2, 4): lo, hi)."""
        return (self.b.read(self.node, self.count, np.int32),
                self.b.read(self.box, 2 * self.count, np.dtype((np.float32, 4))).reshape(-1, 2, 4))


def split_top(clusters: np.ndarray, lo: np.ndarray, hi: np.ndarray, first_node: int):
    """Step 2's binned SAH split of the (two or more) clusters, nodes of the tree with boxes lo..hi,
    down to single clusters, level by level with whole-array operations. A segment gets as many
    bins as it has clusters, up to MAX_BINS, and one whose centroids coincide is halved by count.
    Returns the new nodes, numbered from first_node, as batches (left, right, lo, hi) from the
    bottom level up, and the root."""
    count = len(clusters)
    # one row per cluster, moved as one: its node (int32 bits), lo, hi and centroid
    rows = np.empty((count, 10), np.float32)
    rows[:, 0] = np.asarray(clusters, np.int32).view(np.float32)
    rows[:, 1:4], rows[:, 4:7], rows[:, 7:10] = lo, hi, (lo + hi) * 0.5
    levels = []     # per level: each segment's two halves' node or cluster, and its box
    starts, counts = np.array([0]), np.array([count])
    while len(starts):
        bins = np.clip(2 ** np.ceil(np.log2(counts)).astype(np.int64), 2, MAX_BINS)
        by_bins = np.argsort(bins, kind="stable")    # segments of one bin count lie together
        starts, counts, bins = starts[by_bins], counts[by_bins], bins[by_bins]
        seg = np.repeat(np.arange(len(starts)), counts)
        offsets = np.concatenate([[0], np.cumsum(counts)[:-1]])
        pos = np.arange(seg.size) - offsets[seg] + starts[seg]
        n_seg = len(starts)
        box_lo, box_hi = np.empty((n_seg, 3), np.float32), np.empty((n_seg, 3), np.float32)
        cost, goes_left = np.empty(n_seg), np.empty(seg.size, bool)
        for b in np.unique(bins):
            s0, s1 = np.searchsorted(bins, b), np.searchsorted(bins, b, side="right")
            p0, p1 = offsets[s0], offsets[s1] if s1 < n_seg else seg.size
            r = np.take(rows, pos[p0:p1], axis=0)
            box_lo[s0:s1], box_hi[s0:s1], cost[s0:s1], goes_left[p0:p1] = _best_splits(
                r[:, 1:4], r[:, 4:7], r[:, 7:10], seg[p0:p1] - s0, offsets[s0:s1] - p0, s1 - s0, b)

        # partition each segment stably by its split, or in halves where the centroids coincide
        rank = pos - starts[seg]
        goes_left = np.where(np.isfinite(cost)[seg], goes_left, rank < counts[seg] // 2)
        n_left = np.add.reduceat(goes_left.astype(np.int64), offsets)
        left_before = np.cumsum(goes_left) - goes_left
        left_rank = left_before - left_before[offsets][seg]
        new_pos = starts[seg] + np.where(goes_left, left_rank, n_left[seg] + rank - left_rank)
        moved = np.arange(count)
        moved[new_pos] = pos
        rows = np.take(rows, moved, axis=0)     # one gather (np.take) of whole rows
        levels.append((starts, n_left, counts, box_lo, box_hi))
        halves = np.concatenate([np.column_stack([starts, n_left]),
                                 np.column_stack([starts + n_left, counts - n_left])])
        starts, counts = halves[halves[:, 1] > 1].T

    # nodes bottom-up, each level's batch after the ones below it: a half of one cluster is the
    # cluster itself, a larger half the node made for it one level down (at the half's start)
    clusters = rows[:, 0].copy().view(np.int32)
    made_at = np.empty(count, np.int32)
    batches = []
    for starts, n_left, counts, box_lo, box_hi in reversed(levels):
        left = np.where(n_left > 1, made_at[starts], clusters[starts])
        right = np.where(counts - n_left > 1, made_at[starts + n_left], clusters[starts + n_left])
        made_at[starts] = first_node + np.arange(len(starts))
        first_node += len(starts)
        batches.append((left, right, box_lo, box_hi))
    return batches, int(made_at[0])


def _best_splits(lo, hi, cen, seg, offsets, n_seg, bins):
    """For each segment of the clusters (boxes lo..hi, centroids cen, laid end to end): its box,
    the cost of its best SAH split over `bins` bins per axis, and for each cluster whether it
    goes left. A segment whose centroids all coincide gets cost inf."""
    box_lo = np.minimum.reduceat(lo, offsets)
    box_hi = np.maximum.reduceat(hi, offsets)
    c_lo = np.minimum.reduceat(cen, offsets)
    extent = np.maximum.reduceat(cen, offsets) - c_lo
    scale = np.divide(bins, extent, out=np.zeros_like(extent), where=extent > 0)
    sizes = np.diff(np.append(offsets, len(seg)))
    bin_of = np.minimum(((cen - np.repeat(c_lo, sizes, axis=0)) * np.repeat(scale, sizes, axis=0))
                        .astype(np.int32), bins - 1)                                   # (M, 3)

    # per (bin, segment, split axis): how many clusters, and the box around them; the bin is the
    # outer axis so that the sweeps run over contiguous slices (int32: fewer than 2^31 cells)
    cell = (bin_of * np.int32(n_seg) + seg[:, None].astype(np.int32)) * np.int32(3) \
        + np.arange(3, dtype=np.int32)                                                 # (M, 3)
    count = np.bincount(cell.ravel(), minlength=bins * n_seg * 3).reshape(bins, n_seg, 3)
    bin_lo = np.full(bins * n_seg * 3 * 3, np.inf, np.float32)
    bin_hi = np.full(bins * n_seg * 3 * 3, -np.inf, np.float32)
    for axis in range(3):   # ufunc.at is fastest on flat arrays
        first = cell[:, axis] * np.int32(3)
        for c in range(3):
            at = first + np.int32(c)
            np.minimum.at(bin_lo, at, lo[:, c])
            np.maximum.at(bin_hi, at, hi[:, c])
    bin_lo = bin_lo.reshape(bins, n_seg, 3, 3)
    bin_hi = bin_hi.reshape(bins, n_seg, 3, 3)

    # split i puts bins 0..i on the left
    n_left = np.cumsum(count, axis=0)[:-1]
    n_right = n_left[-1:] + count[-1:] - n_left
    a_left = _sweep(bin_lo, bin_hi, reverse=False)[:-1]
    a_right = _sweep(bin_lo, bin_hi, reverse=True)[1:]
    valid = (n_left > 0) & (n_right > 0)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        cost = TRAVERSAL_COST + np.where(valid, n_left * a_left + n_right * a_right, 0.0) \
            / surface_area(box_lo, box_hi)[:, None]
    cost = np.where(valid, cost, np.inf).transpose(1, 2, 0).reshape(n_seg, -1)
    best = np.argmin(cost, axis=1)
    axis, split = best // (bins - 1), best % (bins - 1)
    goes_left = bin_of[np.arange(seg.size), axis[seg]] <= split[seg]
    return box_lo, box_hi, cost[np.arange(n_seg), best], goes_left


def _sweep(box_lo, box_hi, reverse):
    """Running union of the bins' boxes, bin axis first: out[i] bounds bins 0..i (or i..end)."""
    lo, hi = box_lo.copy(), box_hi.copy()
    steps = range(len(lo) - 2, -1, -1) if reverse else range(1, len(lo))
    for i in steps:
        j = i + 1 if reverse else i - 1
        np.minimum(lo[i], lo[j], out=lo[i])
        np.maximum(hi[i], hi[j], out=hi[i])
    return surface_area(lo, hi)



def _flatten(tree: _Tree, root: int, num_spheres: int) -> BVH:
    """Step 3 on the device (kernels/build/collapse.cl): sweeps over the batches, then the 4-wide
    nodes and the primitives' order read back."""
    b, n, size = tree.b, tree.n, tree.made
    prims, cost = b.filled(np.int32(1), size), b.filled(np.float32(1), size)
    sah_leaf, inner = b.filled(np.uint8(0), size), b.filled(np.uint8(0), size)
    depth, below = b.filled(np.int32(0), size), b.filled(np.int32(0), size)
    number, first_prim = b.filled(np.int32(0), size), b.filled(np.int32(0), size)
    b.write(inner, np.ones(1, np.uint8), root)
    for first, count in tree.batches:
        b.launch("collapse_up", count, tree.child, tree.box, np.int32(first), np.int32(count),
                 prims, cost, sah_leaf)
    for first, count in reversed(tree.batches):
        b.launch("mark_inner_down", count, tree.child, np.int32(first), np.int32(count), np.int32(n),
                 sah_leaf, inner, depth)
    for first, count in tree.batches:
        b.launch("count_inner_up", count, tree.child, np.int32(first), np.int32(count), inner, depth, below)
    for first, count in reversed(tree.batches):
        b.launch("number_down", count, tree.child, np.int32(first), np.int32(count), prims, inner,
                 depth, below, number, first_prim)
    num_nodes = int(b.read(below, 1, np.int32, root)[0])
    nodes, order, max_depth = b.buffer(num_nodes * BVH_NODE.itemsize), b.buffer(n * 4), b.filled(np.int32(0), 1)
    b.launch("write_nodes", size, tree.child, tree.box, np.int32(size), np.int32(n), np.int32(num_spheres),
             inner, number, first_prim, prims, depth, nodes, order, max_depth)
    return BVH(b.read(nodes, num_nodes, BVH_NODE), b.read(order, n, np.int32).astype(np.int64),
               int(b.read(max_depth, 1, np.int32)[0]), float(b.read(cost, 1, np.float32, root)[0]))

