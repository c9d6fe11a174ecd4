"""A bounding volume hierarchy over spheres and triangles together, flattened into the BVH_NODE
array that kernels/bvh.cl walks. Built in three steps:

1. Bottom-up by PLOC, parallel locally-ordered clustering (Meister and Bittner, IEEE TVCG 2018).
   The primitives are sorted along a 63-bit Morton curve of their centroids; each pass, every
   cluster finds the cluster within RADIUS places of it in that order whose union with it has the
   smallest surface area (kernels/build/ploc.cl, on an OpenCL device), and mutual nearest
   neighbours merge into one cluster in the place of the first. Passes repeat until one cluster
   in TOP_FRACTION is left.
2. Over the remaining clusters, two candidate tops: PLOC's passes continued, and a top-down split
   by the binned surface area heuristic (Wald, "On fast Construction of SAH-based Bounding Volume
   Hierarchies", 2007); the one of smaller SAH cost is kept. PLOC's greedy merges of large
   clusters make poor top levels on evenly spread primitives (a quarter more traversal time on
   spheres64k), the binned split poor ones on the teapot over its floor (a sixth more SAH cost),
   and over at most TOP_MAX clusters both are cheap.
3. Collapsed by the SAH (as pbrt-v4's builder decides): a subtree of at most MAX_LEAF_SIZE
   primitives becomes one leaf where that is cheaper than its split, and laid out depth-first.

Leaves hold one kind of primitive (kernels/types.h): spheres and triangles are built apart and
their two trees joined at the root. Nodes are made in batches (a PLOC pass, a level of the top
split) whose members depend only on earlier batches below them, so the sweeps of step 3 run batch
by batch with whole-array operations: no Python code runs per node.
"""

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pyopencl as cl

from app.types import BVH_NODE

MAX_LEAF_SIZE = 4
MAX_DEPTH = 30              # kernels/bvh.cl keeps a 32-entry stack
TRAVERSAL_COST = 0.5        # relative to one primitive test, as in pbrt-v4's BVH build
RADIUS = 8                  # PLOC's search radius: 8 and 16 give trees of the same SAH cost here
TOP_FRACTION = 8            # PLOC stops at one cluster in this many primitives ...
TOP_MAX = 16384             # ... or at this many clusters, whichever is fewer
MORTON_BITS = 21            # per axis: 63 bits in all
MAX_BINS = 16
WORK_GROUP = 64


@dataclass
class BVH:
    nodes: np.ndarray       # BVH_NODE array; node 0 is the root
    order: np.ndarray       # primitive i in the BVH's order is primitive order[i] of the input
    depth: int              # of the deepest leaf, the root's children being at depth 1


def primitive_boxes(spheres: np.ndarray, triangles: np.ndarray):
    """Boxes of spheres ((S, 4) centre and radius) followed by triangles ((T, 3, 3) corners), in
    float32 as the kernels see them."""
    spheres = np.asarray(spheres, np.float32).reshape(-1, 4)
    triangles = np.asarray(triangles, np.float32).reshape(-1, 3, 3)
    lo = np.concatenate([spheres[:, :3] - spheres[:, 3:], triangles.min(axis=1)])
    hi = np.concatenate([spheres[:, :3] + spheres[:, 3:], triangles.max(axis=1)])
    return lo, hi


def surface_area(lo, hi):
    d = np.maximum(hi - lo, 0)
    return 2 * (d[..., 0] * d[..., 1] + d[..., 1] * d[..., 2] + d[..., 2] * d[..., 0])


def sah_cost(bvh: BVH) -> float:
    """The tree's SAH cost relative to its root box: TRAVERSAL_COST per inner node visited plus one
    per primitive tested, each weighted by its box's area (MacDonald and Booth 1990)."""
    c = bvh.nodes["child"]
    lo, hi = c["lo"].astype(np.float64), c["hi"].astype(np.float64)
    root = surface_area(lo[0].min(axis=0), hi[0].max(axis=0))
    areas = surface_area(lo, hi).reshape(-1)
    count = c["count"].reshape(-1)
    inner = count == 0
    return float(TRAVERSAL_COST * (1 + areas[inner].sum() / root)
                 + (np.abs(count[~inner]) * areas[~inner]).sum() / root)


class Builder:
    """kernels/build/ploc.cl on one OpenCL device, with buffers that grow as needed."""

    def __init__(self, queue: cl.CommandQueue):
        from app.device import build_cached
        from app.resources import resource_dir

        self.queue = queue
        source = (resource_dir("kernels") / "build" / "ploc.cl").read_text()
        self.find_nearest = build_cached(queue.context, queue.device, source, []).program.find_nearest
        self.capacity = 0

    def nearest(self, boxes: np.ndarray) -> np.ndarray:
        """Each cluster's nearest neighbour among the RADIUS on either side; boxes: (C, 2, 4)
        float32, lo then hi."""
        count = len(boxes)
        if count > self.capacity:
            self.capacity = count
            self.box_buf = cl.Buffer(self.queue.context, cl.mem_flags.READ_ONLY, boxes.nbytes)
            self.nearest_buf = cl.Buffer(self.queue.context, cl.mem_flags.WRITE_ONLY, count * 4)
        out = np.empty(count, np.int32)
        cl.enqueue_copy(self.queue, self.box_buf, boxes, is_blocking=False)
        groups = -(-count // WORK_GROUP)     # one work-group size, so PoCL compiles the kernel once
        self.find_nearest(self.queue, (groups * WORK_GROUP,), (WORK_GROUP,), self.box_buf,
                          np.int32(count), np.int32(RADIUS), self.nearest_buf)
        cl.enqueue_copy(self.queue, out, self.nearest_buf, is_blocking=True)
        return out


_builders: dict = {}


def builder_for(queue: cl.CommandQueue = None) -> Builder:
    """The builder on `queue`'s device, or, without one, on the first device (GPUs first) whose
    platform builds it; made once per queue."""
    if queue not in _builders:
        _builders[queue] = Builder(queue) if queue is not None else _first_working_builder()
    return _builders[queue]


def _first_working_builder() -> Builder:
    from app.device import list_devices
    from app.errors import UserError

    for d in sorted(list_devices(), key=lambda d: d.kind != "GPU"):
        try:
            return Builder(cl.CommandQueue(cl.Context([d.device])))
        except cl.Error:
            continue
    raise UserError("no OpenCL device can build the BVH: install an OpenCL driver "
                    "(on Debian/Ubuntu, 'apt install pocl-opencl-icd' runs on the CPU)")


class _Tree:
    """A binary tree under construction: primitives are nodes 0..n-1, and each new node gets the
    next number. batches: slices of node numbers, each depending only on earlier ones."""

    def __init__(self, lo, hi):
        self.n = len(lo)
        size = max(2 * self.n - 1, 1)
        self.left = np.full(size, -1, np.int32)
        self.right = np.full(size, -1, np.int32)
        self.lo = np.zeros((size, 3), np.float32)
        self.hi = np.zeros((size, 3), np.float32)
        self.lo[:self.n], self.hi[:self.n] = lo, hi
        self.made = self.n
        self.batches: list[slice] = []

    def add(self, left, right, lo, hi) -> np.ndarray:
        """New nodes over the given children, as one batch; returns their numbers."""
        b = slice(self.made, self.made + len(left))
        self.left[b], self.right[b], self.lo[b], self.hi[b] = left, right, lo, hi
        self.made = b.stop
        self.batches.append(b)
        return np.arange(b.start, b.stop, dtype=np.int32)

    def mark(self):
        return self.made, len(self.batches)

    def area_since(self, mark) -> float:
        return float(surface_area(self.lo[mark[0]:self.made].astype(np.float64),
                                  self.hi[mark[0]:self.made].astype(np.float64)).sum())

    def cut(self, mark) -> "_Cut":
        """Takes back the nodes made since `mark`, returning them."""
        made, batches = mark
        b = slice(made, self.made)
        taken = _Cut(self.area_since(mark), self.batches[batches:], self.left[b].copy(),
                     self.right[b].copy(), self.lo[b].copy(), self.hi[b].copy())
        self.made, self.batches = made, self.batches[:batches]
        return taken

    def paste(self, cut: "_Cut"):
        """Puts back nodes taken by cut() at the same mark."""
        b = slice(self.made, self.made + len(cut.left))
        self.left[b], self.right[b], self.lo[b], self.hi[b] = cut.left, cut.right, cut.lo, cut.hi
        self.made = b.stop
        self.batches += cut.batches


@dataclass
class _Cut:
    area: float
    batches: list
    left: np.ndarray
    right: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


def build_bvh(lo: np.ndarray, hi: np.ndarray, num_spheres: int = None,
              queue: cl.CommandQueue = None, progress: Callable[[float], None] = None) -> BVH:
    """A BVH over N >= 1 primitives given by their boxes lo..hi ((N, 3) each, finite): spheres
    first (num_spheres of them; default: all), then triangles, which leaves keep apart. The
    clustering runs on `queue`'s device (default: builder_for()'s); progress, if given, is called
    with the fraction done after each PLOC pass."""
    lo, hi = np.asarray(lo, np.float32), np.asarray(hi, np.float32)
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise ValueError("build_bvh: primitive boxes must be finite")
    n = len(lo)
    num_spheres = n if num_spheres is None else num_spheres
    tree = _Tree(lo, hi)
    if n == 1:
        return _flatten(tree, 0, num_spheres)
    builder = builder_for(queue)
    merged = 0

    def report(count):   # n - 1 merges in all, the join of the kinds' trees included
        nonlocal merged
        merged += count
        if progress:
            progress(merged / (n - 1))

    roots = [_build_kind(tree, builder, first, stop, report)
             for first, stop in ((0, num_spheres), (num_spheres, n)) if stop > first]
    if len(roots) == 2:
        a, b = roots
        roots = tree.add([a], [b], [np.minimum(tree.lo[a], tree.lo[b])], [np.maximum(tree.hi[a], tree.hi[b])])
        report(1)
    return _flatten(tree, roots[0], num_spheres)


def _build_kind(tree: _Tree, builder: Builder, first: int, stop: int, report) -> int:
    """Steps 1 and 2 over the primitives first..stop-1; returns the root."""
    node = (_morton_order(tree.lo[first:stop], tree.hi[first:stop]) + first).astype(np.int32)
    boxes = np.zeros((len(node), 2, 4), np.float32)
    np.take(tree.lo, node, axis=0, out=boxes[:, 0, :3], mode="clip")
    np.take(tree.hi, node, axis=0, out=boxes[:, 1, :3], mode="clip")
    node, boxes = _cluster(tree, builder, node, boxes, max(1, min(len(node) // TOP_FRACTION, TOP_MAX)), report)
    if len(node) == 1:
        return int(node[0])
    # two candidate tops over the remaining clusters; the one of smaller SAH cost is kept (the
    # clusters below are the same, so the sum of the new nodes' areas decides)
    mark = tree.mark()
    split_root = _split_top(tree, node.copy(), boxes[:, 0, :3].copy(), boxes[:, 1, :3].copy())
    split_top = tree.cut(mark)
    cluster_root = _cluster(tree, builder, node, boxes, 1, report)[0][0]
    if split_top.area < tree.area_since(mark):
        tree.cut(mark)
        tree.paste(split_top)
        return split_root
    return int(cluster_root)


def _cluster(tree: _Tree, builder: Builder, node, boxes, stop, report):
    """Step 1: PLOC passes over the clusters `node` (boxes: (C, 2, 4), lo then hi, in Morton
    order) until `stop` clusters are left; returns those and their boxes. Each pass compacts into
    the other of two buffers: fresh memory is slow to touch on some virtual machines."""
    spare_node, spare_boxes = np.empty_like(node), np.empty_like(boxes)
    while len(node) > stop:
        nearest = builder.nearest(boxes)
        index = np.arange(len(node), dtype=np.int32)
        mutual = nearest[nearest] == index
        i = np.flatnonzero(mutual & (index < nearest))
        j = nearest[i]
        lo, hi = np.minimum(boxes[i, 0], boxes[j, 0]), np.maximum(boxes[i, 1], boxes[j, 1])
        node[i] = tree.add(node[i], node[j], lo[:, :3], hi[:, :3])
        boxes[i, 0], boxes[i, 1] = lo, hi
        keep = ~mutual | (index < nearest)
        m = len(node) - len(i)
        np.compress(keep, node, out=spare_node[:m])
        np.compress(keep, boxes, axis=0, out=spare_boxes[:m])
        node, spare_node = spare_node[:m], node
        boxes, spare_boxes = spare_boxes[:m], boxes
        report(len(i))
    return node, boxes


def _morton_order(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The indices of the boxes sorted along a Morton curve of their centroids, in their bounds."""
    cen = lo + hi                               # twice the centroids: the order is the same
    c_lo, c_hi = cen.min(axis=0), cen.max(axis=0)
    scale = np.divide((1 << MORTON_BITS) - 1, c_hi - c_lo, out=np.zeros(3, np.float32), where=c_hi > c_lo)
    cen -= c_lo
    cen *= scale
    code = np.zeros(len(cen), np.uint64)
    v, t = np.empty(len(cen), np.uint64), np.empty(len(cen), np.uint64)
    for axis in range(3):   # the magic-number spread of 21 bits to every third bit, in place
        v[:] = cen[:, axis]
        for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F),
                            (4, 0x10C30C30C30C30C3), (2, 0x1249249249249249)):
            np.left_shift(v, np.uint64(shift), out=t)
            v |= t
            v &= np.uint64(mask)
        v <<= np.uint64(2 - axis)
        code |= v
    return np.argsort(code)   # not stable, but deterministic, and five times faster here


def _split_top(tree: _Tree, clusters: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> int:
    """Step 2: the binned SAH split of the clusters (nodes of the tree with boxes lo..hi) down to
    single clusters, level by level with whole-array operations; returns the root. A segment
    gets as many bins as it has clusters, up to MAX_BINS, and one whose centroids coincide is
    halved by count."""
    count = len(clusters)
    if count == 1:
        return int(clusters[0])
    cen = (lo + hi) * 0.5
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
            box_lo[s0:s1], box_hi[s0:s1], cost[s0:s1], goes_left[p0:p1] = _best_splits(
                lo[pos[p0:p1]], hi[pos[p0:p1]], cen[pos[p0:p1]], seg[p0:p1] - s0, offsets[s0:s1] - p0, s1 - s0, b)

        # partition each segment stably by its split, or in halves where the centroids coincide
        rank = pos - starts[seg]
        goes_left = np.where(np.isfinite(cost)[seg], goes_left, rank < counts[seg] // 2)
        n_left = np.add.reduceat(goes_left.astype(np.int64), offsets)
        left_before = np.cumsum(goes_left) - goes_left
        left_rank = left_before - left_before[offsets][seg]
        new_pos = starts[seg] + np.where(goes_left, left_rank, n_left[seg] + rank - left_rank)
        for a in (clusters, lo, hi, cen):
            a[new_pos] = a[pos].copy()
        levels.append((starts, n_left, counts, box_lo, box_hi))
        halves = np.concatenate([np.column_stack([starts, n_left]),
                                 np.column_stack([starts + n_left, counts - n_left])])
        starts, counts = halves[halves[:, 1] > 1].T

    # nodes bottom-up, each level's batch after the ones below it: a half of one cluster is the
    # cluster itself, a larger half the node made for it one level down (at the half's start)
    made_at = np.empty(count, np.int32)
    for starts, n_left, counts, box_lo, box_hi in reversed(levels):
        left = np.where(n_left > 1, made_at[starts], clusters[starts])
        right = np.where(counts - n_left > 1, made_at[starts + n_left], clusters[starts + n_left])
        made_at[starts] = tree.add(left, right, box_lo, box_hi)
    return int(made_at[0])


def _best_splits(lo, hi, cen, seg, offsets, n_seg, bins):
    """For each segment of the clusters (boxes lo..hi, centroids cen, laid end to end): its box,
    the cost of its best SAH split over `bins` bins per axis, and for each cluster whether it
    goes left. A segment whose centroids all coincide gets cost inf."""
    box_lo = np.minimum.reduceat(lo, offsets)
    box_hi = np.maximum.reduceat(hi, offsets)
    c_lo = np.minimum.reduceat(cen, offsets)
    extent = np.maximum.reduceat(cen, offsets) - c_lo
    scale = np.divide(bins, extent, out=np.zeros_like(extent), where=extent > 0)
    bin_of = np.minimum(((cen - c_lo[seg]) * scale[seg]).astype(np.int32), bins - 1)   # (M, 3)

    # per (bin, segment, split axis): how many clusters, and the box around them; the bin is the
    # outer axis so that the sweeps run over contiguous slices
    cell = (bin_of * n_seg + seg[:, None]) * 3 + np.arange(3)                          # (M, 3)
    count = np.bincount(cell.ravel(), minlength=bins * n_seg * 3).reshape(bins, n_seg, 3)
    bin_lo = np.full(bins * n_seg * 3 * 3, np.inf, np.float32)
    bin_hi = np.full(bins * n_seg * 3 * 3, -np.inf, np.float32)
    for axis in range(3):   # ufunc.at is fastest on flat arrays
        for c in range(3):
            np.minimum.at(bin_lo, cell[:, axis] * 3 + c, lo[:, c])
            np.maximum.at(bin_hi, cell[:, axis] * 3 + c, hi[:, c])
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
    """Step 3: the binary tree collapsed into leaves by the SAH and laid out as BVH_NODEs in
    depth-first order, each leaf's primitives consecutive."""
    n, left, right = tree.n, tree.left, tree.right
    if n == 1:   # a lone primitive: the root holds it in both slots (tested twice, harmlessly)
        nodes = np.zeros(1, BVH_NODE)
        lo, hi = tree.lo[:1].copy(), tree.hi[:1].copy()
        _widen(lo, hi)
        nodes["child"]["lo"], nodes["child"]["hi"] = lo, hi
        nodes["child"]["count"] = 1 if num_spheres else -1
        return BVH(nodes, np.zeros(1, np.int64), 1)

    # bottom-up: primitives under each node, and its SAH cost relative to its own area (float32
    # areas may overflow to inf in huge scenes, which only makes a leaf less likely)
    size = len(left)
    count = np.ones(size, np.int32)
    with np.errstate(over="ignore", invalid="ignore"):
        area = _half_area(tree.lo, tree.hi)
    cost = np.ones(size, np.float32)
    sah_leaf = np.zeros(size, bool)
    for b in tree.batches:
        l, r = left[b], right[b]
        count[b] = count[l] + count[r]
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            split = TRAVERSAL_COST + np.divide(area[l] * cost[l] + area[r] * cost[r], area[b],
                                               out=cost[l] + cost[r], where=area[b] > 0)
        sah_leaf[b] = (count[b] <= MAX_LEAF_SIZE) & (count[b] <= split)
        cost[b] = np.where(sah_leaf[b], count[b], split)

    # top-down: depth; a node is an inner BVH node unless it is a primitive, a leaf by the SAH,
    # inside a leaf, or at MAX_DEPTH (where the leaf keeps all its primitives). The root is inner.
    depth = np.zeros(size, np.int32)
    inner = np.zeros(size, bool)
    inner[root] = True
    for b in reversed(tree.batches):
        parents = np.flatnonzero(inner[b]) + b.start
        for child in (left[parents], right[parents]):
            depth[child] = depth[parents] + 1
            inner[child] = (child >= n) & ~sah_leaf[child] & (depth[child] < MAX_DEPTH)

    # bottom-up: inner nodes in each subtree; top-down: each inner node's number in depth-first
    # order, and each node's first primitive
    nodes_below = inner.astype(np.int32)
    for b in tree.batches:
        nodes_below[b] = np.where(inner[b], 1 + nodes_below[left[b]] + nodes_below[right[b]], 0)
    number = np.zeros(size, np.int32)
    first = np.zeros(size, np.int32)
    for b in reversed(tree.batches):
        first[left[b]] = first[b]
        first[right[b]] = first[b] + count[left[b]]
        number[left[b]] = number[b] + 1
        number[right[b]] = number[b] + 1 + nodes_below[left[b]]
    order = np.empty(n, np.int64)
    order[first[:n]] = np.arange(n)

    parents = np.empty(np.count_nonzero(inner), np.int32)
    parents[number[inner]] = np.flatnonzero(inner)                    # in depth-first order
    children = np.stack([left[parents], right[parents]], axis=1)     # (nodes, 2)

    # BVH_NODE's 16 words: per child lo, index, hi, count; filled in place (np.take with out),
    # since fresh memory is slow to touch on some virtual machines
    _widen(tree.lo, tree.hi)
    words = np.zeros((len(parents), 2, 8), np.int32)
    np.take(tree.lo.view(np.int32), children, axis=0, out=words[:, :, 0:3], mode="clip")
    np.take(tree.hi.view(np.int32), children, axis=0, out=words[:, :, 4:7], mode="clip")
    # a leaf indexes its kind's own array (kernels/types.h), and a triangle leaf's count is
    # negative; in BVH order the spheres' tree comes first, so triangles' numbers are shifted
    is_inner = inner[children]
    index = first[children]
    is_triangle = index >= num_spheres
    np.subtract(index, num_spheres, out=index, where=is_triangle)
    np.copyto(index, number[children], where=is_inner)
    words[:, :, 3] = index
    leaf_count = count[children]
    np.negative(leaf_count, out=leaf_count, where=is_triangle)
    leaf_count[is_inner] = 0
    words[:, :, 7] = leaf_count
    nodes = words.reshape(len(parents), 16).view(BVH_NODE).reshape(-1)
    return BVH(nodes, order, int(depth[children][~is_inner].max()))


def _half_area(lo, hi):
    """Half the surface areas of boxes, with few temporary arrays."""
    d = hi - lo
    np.maximum(d, 0, out=d)
    area = d[:, 0] * d[:, 1]
    area += d[:, 1] * d[:, 2]
    area += d[:, 2] * d[:, 0]
    return area


def _widen(lo, hi):
    """Widens boxes in place by one or two float steps, covering the rounding of centre -/+ radius
    and of the corners' float32 values: x -/+ (|x| 2^-23 + FLT_MIN) rounds to at least the next
    float outward (|x| 2^-23 is one to two units in the last place of x), and moves 0 too."""
    step = np.empty_like(lo)
    for box, outward in ((lo, np.subtract), (hi, np.add)):
        np.abs(box, out=step)
        step *= np.float32(2.0 ** -23)
        step += np.finfo(np.float32).tiny
        outward(box, step, out=box)
