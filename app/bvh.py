"""A bounding volume hierarchy over spheres and triangles together, built top-down with the binned surface area heuristic
(Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007) and flattened into
the BVH_NODE array that kernels/intersect.cl walks.

The build is level-synchronous: every node of one tree level is split at once with whole-array
NumPy operations (segmented reductions, bincount and ufunc.at), so no Python code runs per node.
A node gets as many bins as it has primitives, up to 16, which keeps the work of a level
proportional to the primitives in it.

Leaves hold one kind of primitive (kernels/types.h): a node that would become a leaf over both
spheres and triangles is split by kind instead.
"""

from dataclasses import dataclass

import numpy as np

from app.types import BVH_NODE

MAX_BINS = 16
MAX_LEAF_SIZE = 4
MAX_DEPTH = 30              # kernels/intersect.cl keeps a 32-entry stack
TRAVERSAL_COST = 0.5        # relative to one primitive test, as in pbrt-v4's BVH build


@dataclass
class BVH:
    nodes: np.ndarray       # BVH_NODE array; node 0 is the root
    order: np.ndarray       # primitive i in the BVH's order is primitive order[i] of the input
    depth: int


def _surface_area(lo, hi):
    d = np.maximum(hi - lo, 0.0)
    return 2.0 * (d[..., 0] * d[..., 1] + d[..., 1] * d[..., 2] + d[..., 2] * d[..., 0])


def _segments(starts, counts):
    """Positions of the segments [start, start + count) laid end to end, each one's segment
    number, and where each segment begins in that layout."""
    seg = np.repeat(np.arange(len(starts)), counts)
    offsets = np.concatenate([[0], np.cumsum(counts)[:-1]])
    pos = np.arange(seg.size) - offsets[seg] + starts[seg]
    return pos, seg, offsets


def _sweep(box_lo, box_hi, reverse):
    """Running union of the bins' boxes, bin axis first: out[i] bounds bins 0..i (or i..end)."""
    lo, hi = box_lo.copy(), box_hi.copy()
    steps = range(len(lo) - 2, -1, -1) if reverse else range(1, len(lo))
    for i in steps:
        j = i + 1 if reverse else i - 1
        np.minimum(lo[i], lo[j], out=lo[i])
        np.maximum(hi[i], hi[j], out=hi[i])
    return _surface_area(lo, hi)


def _best_splits(lo, hi, cen, seg, offsets, n_seg, bins):
    """For each segment of the primitives (boxes lo..hi, centroids cen, laid end to end): its
    box, the cost of its best SAH split over `bins` bins per axis, and for each primitive
    whether it goes left. A segment whose centroids all coincide gets cost inf."""
    box_lo = np.minimum.reduceat(lo, offsets)
    box_hi = np.maximum.reduceat(hi, offsets)
    c_lo = np.minimum.reduceat(cen, offsets)
    extent = np.maximum.reduceat(cen, offsets) - c_lo
    scale = np.divide(bins, extent, out=np.zeros_like(extent), where=extent > 0)
    bin_of = np.minimum(((cen - c_lo[seg]) * scale[seg]).astype(np.int32), bins - 1)   # (M, 3)

    # per (bin, segment, split axis): how many primitives, and the box around them; the bin is the
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
    with np.errstate(invalid="ignore", divide="ignore"):
        cost = TRAVERSAL_COST + np.where(valid, n_left * a_left + n_right * a_right, 0.0) \
            / _surface_area(box_lo, box_hi)[:, None]
    cost = np.where(valid, cost, np.inf).transpose(1, 2, 0).reshape(n_seg, -1)
    best = np.argmin(cost, axis=1)
    axis, split = best // (bins - 1), best % (bins - 1)
    goes_left = bin_of[np.arange(seg.size), axis[seg]] <= split[seg]
    return box_lo, box_hi, cost[np.arange(n_seg), best], goes_left


def _bins_for(counts):
    return np.clip(2 ** np.ceil(np.log2(np.maximum(counts, 2))).astype(np.int64), 2, MAX_BINS)


def primitive_boxes(spheres: np.ndarray, triangles: np.ndarray):
    """Boxes and centroids of spheres ((S, 4) centre and radius) followed by triangles ((T, 3, 3)
    corners), in float32 as the kernels see them."""
    spheres = np.asarray(spheres, np.float32).reshape(-1, 4)
    triangles = np.asarray(triangles, np.float32).reshape(-1, 3, 3)
    lo = np.concatenate([spheres[:, :3] - spheres[:, 3:], triangles.min(axis=1)])
    hi = np.concatenate([spheres[:, :3] + spheres[:, 3:], triangles.max(axis=1)])
    return lo, hi


def build_bvh(lo: np.ndarray, hi: np.ndarray, is_triangle: np.ndarray = None) -> BVH:
    """A BVH over N >= 1 primitives given by their boxes lo..hi ((N, 3) each); is_triangle marks
    the primitives that leaves must keep apart from the others (default: none)."""
    n = len(lo)
    kind = np.zeros(n, bool) if is_triangle is None else np.asarray(is_triangle, bool)
    # the primitives' boxes, centroids and kinds, kept in the order of `order`
    boxes = np.concatenate([lo, hi, (np.asarray(lo, np.float64) + hi) / 2, kind[:, None]], axis=1)
    boxes = boxes.astype(np.float32)
    order = np.arange(n)
    # node fields, filled slot by slot; node 0 is the root
    child_lo = np.zeros((n, 2, 3), np.float32)
    child_hi = np.zeros((n, 2, 3), np.float32)
    child_index = np.zeros((n, 2), np.int64)
    child_count = np.zeros((n, 2), np.int64)
    n_nodes = 1

    # open segments of `order`: start, count, which node slot will point at them (-1: the root)
    starts, counts = np.array([0]), np.array([n])
    parent, slot = np.array([-1]), np.array([0])
    depth = 0
    for depth in range(MAX_DEPTH + 1):
        bins = _bins_for(counts)
        by_bins = np.argsort(bins, kind="stable")    # segments of one bin count lie together
        starts, counts, parent, slot, bins = (a[by_bins] for a in (starts, counts, parent, slot, bins))
        pos, seg, offsets = _segments(starts, counts)
        prims, level = order[pos], boxes[pos]
        n_seg = len(starts)
        box_lo, box_hi = np.empty((n_seg, 3), np.float32), np.empty((n_seg, 3), np.float32)
        cost, goes_left = np.empty(n_seg), np.empty(seg.size, bool)
        for b in np.unique(bins):
            s0, s1 = np.searchsorted(bins, b), np.searchsorted(bins, b, side="right")
            p0, p1 = offsets[s0], offsets[s1] if s1 < n_seg else seg.size
            box_lo[s0:s1], box_hi[s0:s1], cost[s0:s1], goes_left[p0:p1] = _best_splits(
                level[p0:p1, 0:3], level[p0:p1, 3:6], level[p0:p1, 6:9], seg[p0:p1] - s0,
                offsets[s0:s1] - p0, s1 - s0, b)

        is_root = parent < 0
        triangles = level[:, 9] > 0
        n_triangles = np.add.reduceat(triangles.astype(np.int64), offsets)
        mixed = (n_triangles > 0) & (n_triangles < counts)
        wants_leaf = (counts == 1) | ((counts <= MAX_LEAF_SIZE) & (counts <= cost)) | (depth == MAX_DEPTH)
        # a mixed segment that would be a leaf, or that cannot wait longer, is split by kind
        by_kind = mixed & (wants_leaf | (depth >= MAX_DEPTH - 1))
        leaf = wants_leaf & ~mixed & ~is_root
        inner = ~leaf
        new_inner = inner & ~is_root
        node_id = np.zeros(n_seg, np.int64)
        node_id[new_inner] = n_nodes + np.arange(np.count_nonzero(new_inner))
        n_nodes += np.count_nonzero(new_inner)

        # each segment fills in the slot that points at it
        p, s = parent[~is_root], slot[~is_root]
        child_lo[p, s] = box_lo[~is_root]
        child_hi[p, s] = box_hi[~is_root]
        child_index[p, s] = np.where(leaf, starts, node_id)[~is_root]
        child_count[p, s] = np.where(leaf, counts, 0)[~is_root]
        if n == 1:   # a lone primitive: the root holds it in both slots (tested twice, harmlessly)
            child_lo[0], child_hi[0], child_index[0], child_count[0] = box_lo[0], box_hi[0], 0, 1
            break
        if not inner.any():
            break

        # partition each inner segment stably: by kind where it must, by its SAH split, or in
        # halves by count where the centroids coincide
        rank = pos - starts[seg]
        goes_left = np.where(np.isfinite(cost)[seg], goes_left, rank < counts[seg] // 2)
        goes_left = np.where(by_kind[seg], ~triangles, goes_left)
        n_left = np.add.reduceat(goes_left.astype(np.int64), offsets)
        left_before = np.cumsum(goes_left) - goes_left
        left_rank = left_before - left_before[offsets][seg]
        new_pos = starts[seg] + np.where(goes_left, left_rank, n_left[seg] + rank - left_rank)
        keep = inner[seg]
        order[new_pos[keep]] = prims[keep]
        boxes[new_pos[keep]] = level[keep]

        starts, counts, nid, n_left = starts[inner], counts[inner], node_id[inner], n_left[inner]
        starts = np.concatenate([starts, starts + n_left])
        counts = np.concatenate([n_left, counts - n_left])
        parent = np.concatenate([nid, nid])
        slot = np.concatenate([np.zeros_like(nid), np.ones_like(nid)])

    # leaves index their kind's own array (kernels/types.h): spheres and triangles are each
    # kept in BVH order, and a triangle leaf's count is negative
    child_index, child_count = child_index[:n_nodes], child_count[:n_nodes]
    ordered_kind = kind[order]
    local = np.where(ordered_kind, np.cumsum(ordered_kind), np.cumsum(~ordered_kind)) - 1
    leaf = child_count > 0
    first = child_index[leaf]
    child_index[leaf] = local[first]
    child_count[leaf] = np.where(ordered_kind[first], -child_count[leaf], child_count[leaf])

    nodes = np.zeros(n_nodes, BVH_NODE)
    # widen the boxes by one float step, covering the rounding of centre -/+ radius and of the
    # corners' float32 values
    nodes["child"]["lo"] = np.nextafter(child_lo[:n_nodes], np.float32(-np.inf))
    nodes["child"]["hi"] = np.nextafter(child_hi[:n_nodes], np.float32(np.inf))
    nodes["child"]["index"] = child_index
    nodes["child"]["count"] = child_count
    return BVH(nodes, order, depth)
