"""The BVH of a small scene, built on the host in NumPy by the device builder's steps
(app/compiler/bvh.py: build_tree), each as its kernel computes it, in float32 without fused
operations: Morton codes (kernels/build/morton.cl), PLOC's passes (kernels/build/ploc.cl) and the
collapse (kernels/build/collapse.cl), a pass or a sweep over a batch of nodes at once. The tree is
the device's, byte for byte (tests/test_bvh.py). A tree of a few thousand primitives takes
milliseconds here, where the device's builder first needs its program built and, on PoCL, each
of its kernels compiled at its first launch: 1.25 s of a cold `render cornell-box` (32
triangles) on two cores, and 0.06-0.09 s of a warm one (docs/notes/performance-2026-12.md,
twenty-third session). It needs no device, so a small scene's tree is built while the devices
open (compile_before_devices)."""

import numpy as np

from pathtrace.compiler.builder import MAX_DEPTH, MAX_LEAF_SIZE, TRAVERSAL_COST
from pathtrace.compiler.bvh import BVH, BinaryTree, RADIUS, build_bvh, build_tree
from pathtrace.device.types import BVH_NODE

FLT_MAX = np.float32(np.finfo(np.float32).max)


def build_on_host(lo: np.ndarray, hi: np.ndarray, num_spheres: int = None, progress=None) -> BVH:
    """build_bvh's tree (the same arguments but the device's queue), built on the host."""
    lo, hi = np.asarray(lo, np.float32), np.asarray(hi, np.float32)
    num_spheres = len(lo) if num_spheres is None else num_spheres
    if len(lo) <= 1 or not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        return build_bvh(lo, hi, num_spheres)       # a lone primitive's (no device), or its refusal
    return build_tree(HostTree(lo, hi), lo, hi, num_spheres, progress)


class HostTree(BinaryTree):
    """bvh._Tree's binary tree, in host arrays: child (left, right) and box (lo, hi as float4)
    per node."""

    def __init__(self, lo: np.ndarray, hi: np.ndarray):
        super().__init__(len(lo))
        self.child = np.full((2 * self.n - 1, 2), -1, np.int32)
        self.box = np.zeros((2 * self.n - 1, 2, 4), np.float32)
        self.box[:self.n, 0, :3], self.box[:self.n, 1, :3] = lo, hi

    def add(self, left, right, lo, hi) -> np.ndarray:
        count = len(left)
        self.child[self.made:self.made + count] = np.column_stack([left, right])
        self.box[self.made:self.made + count, 0, :3], self.box[self.made:self.made + count, 1, :3] = lo, hi
        return self.made_batch(count)

    def boxes(self, first: int, stop: int) -> np.ndarray:
        return self.box[first:stop]

    def clusters(self, first: int, count: int, c_lo, scale) -> "HostClusters":
        q = (self.box[first:first + count, 0] + self.box[first:first + count, 1] - c_lo) * scale
        q = np.fmin(np.fmax(q, np.float32(0)), np.float32(2097151)).astype(np.uint32)    # clamp's: NaN 0
        codes = _spread_bits(q[:, 0]) << np.uint64(2) | _spread_bits(q[:, 1]) << np.uint64(1) | _spread_bits(q[:, 2])
        order = first + np.argsort(codes).astype(np.int32)      # the device builder's sort
        return HostClusters(order, self.box[order])

    def flatten(self, root: int, num_spheres: int) -> BVH:
        return _collapse(self.child[:self.made], self.box[:self.made, :, :3],
                         [np.arange(f, f + c) for f, c in self.batches], root, self.n, num_spheres)


def _spread_bits(v: np.ndarray) -> np.ndarray:
    x = v.astype(np.uint64) & np.uint64(0x1FFFFF)
    for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F),
                        (4, 0x10C30C30C30C30C3), (2, 0x1249249249249249)):
        x = (x | x << np.uint64(shift)) & np.uint64(mask)
    return x


class HostClusters:
    """bvh._Clusters on the host: the clusters' nodes and boxes in Morton order."""

    def __init__(self, node: np.ndarray, box: np.ndarray):
        self.node, self.box, self.count = node.astype(np.int32), box.copy(), len(node)

    def read(self):
        return self.node, self.box

    def cluster(self, tree: HostTree, stop: int, report) -> int:
        """PLOC's passes until `stop` clusters are left; returns the last cluster's node."""
        while self.count > stop:
            nearest = _nearest(self.box)
            i = np.arange(self.count)
            mutual = nearest[nearest] == i
            merges, survives = mutual & (i < nearest), ~(mutual & (i > nearest))
            first = i[merges]
            partner = nearest[merges]
            new = tree.add(self.node[first], self.node[partner],
                           np.fmin(self.box[first, 0, :3], self.box[partner, 0, :3]),
                           np.fmax(self.box[first, 1, :3], self.box[partner, 1, :3]))
            self.node[first] = new
            self.box[first] = tree.box[new]
            self.node, self.box = self.node[survives], self.box[survives]
            self.count = len(self.node)
            report(len(new))
        return tree.made - 1


def _nearest(box: np.ndarray) -> np.ndarray:
    """find_nearest: for each cluster, the one within RADIUS places whose union with it has the
    smallest area, k ascending and the right one first at each k, ties broken as the kernel
    breaks them."""
    count = len(box)
    lo, hi = box[:, 0, :3], box[:, 1, :3]
    i = np.arange(count)
    best, best_j = np.full(count, np.inf, np.float32), np.full(count, -1, np.int64)
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(1, RADIUS + 1):
            for left, j in ((False, i + k), (True, i - k)):
                inside = (j >= 0) & (j < count)
                jj = np.clip(j, 0, count - 1)
                e = np.minimum(np.fmax(hi, hi[jj]) - np.fmin(lo, lo[jj]), FLT_MAX)
                a = e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 2] * e[:, 0]
                better = (a < best) | (best_j < 0)
                if left:        # a tie with the right one at this k
                    better |= (a == best) & (best_j == i + k) & ((i // k) % 2 == 1)
                better &= inside
                best, best_j = np.where(better, a, best), np.where(better, j, best_j)
    return best_j


def _half_area(box, k):
    e = np.minimum(np.maximum(box[k, 1] - box[k, 0], np.float32(0)), FLT_MAX)
    return e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 2] * e[:, 0]


def _collapse(child, box, batches, root, n, num_spheres) -> BVH:
    """kernels/build/collapse.cl's five sweeps, each over a batch at once (its comments say what
    each computes), in float32 as the kernels compute."""
    size = len(child)
    prims, cost = np.ones(size, np.int32), np.ones(size, np.float32)
    sah_leaf, inner = np.zeros(size, bool), np.zeros(size, bool)
    depth, below = np.zeros(size, np.int32), np.zeros(size, np.int32)
    number, first_prim = np.zeros(size, np.int32), np.zeros(size, np.int32)
    inner[root] = True
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        for k in batches:                                   # collapse_up
            a, b = child[k, 0], child[k, 1]
            count = prims[a] + prims[b]
            area = _half_area(box, k)
            under = _half_area(box, a) * cost[a] + _half_area(box, b) * cost[b]
            split = np.float32(TRAVERSAL_COST) + np.where(area > 0, under / np.where(area > 0, area, 1),
                                                          cost[a] + cost[b]).astype(np.float32)
            leaf = (count <= MAX_LEAF_SIZE) & (count <= split)
            prims[k], cost[k], sah_leaf[k] = count, np.where(leaf, count, split), leaf
    for k in reversed(batches):                             # mark_inner_down
        k = k[inner[k]]
        for c in (child[k, 0], child[k, 1]):
            depth[c] = depth[k] + 1
            inner[c] = (c >= n) & ~sah_leaf[c] & (depth[c] < MAX_DEPTH)
    wide = inner & (depth % 2 == 0)
    for k in batches:                                       # count_inner_up
        below[k] = np.where(inner[k], wide[k] + below[child[k, 0]] + below[child[k, 1]], 0)
    for k in reversed(batches):                             # number_down
        a, b = child[k, 0], child[k, 1]
        first_prim[a], first_prim[b] = first_prim[k], first_prim[k] + prims[a]
        number[a], number[b] = number[k] + wide[k], number[k] + wide[k] + below[a]
    order = np.empty(n, np.int64)                           # write_nodes
    order[first_prim[:n]] = np.arange(n)
    k = np.flatnonzero(inner)
    leaf_below = ~inner[child[k, 0]] | ~inner[child[k, 1]]
    max_depth = int(depth[k[leaf_below]].max()) + 1 if leaf_below.any() else 0
    k = np.flatnonzero(wide)
    slots = []
    for side in (0, 1):
        h = child[k, side]
        split_here = inner[h]
        slots.append(np.where(split_here, child[h, 0], h))
        slots.append(np.where(split_here, child[h, 1], -1))
    slots = np.stack(slots, axis=1)                         # (wide nodes, 4) of node numbers, -1 empty
    nodes = np.zeros(int(below[root]), BVH_NODE)
    at = number[k]
    present = slots >= 0
    s = np.where(present, slots, 0)
    lo = np.where(present[..., None], np.nextafter(box[s, 0], np.float32(-np.inf)), np.float32(np.inf))
    hi = np.where(present[..., None], np.nextafter(box[s, 1], np.float32(np.inf)), np.float32(np.inf))
    for axis, name in enumerate("xyz"):
        nodes[f"lo_{name}"][at], nodes[f"hi_{name}"][at] = lo[..., axis], hi[..., axis]
    spheres = first_prim[s] < num_spheres
    nodes["index"][at] = np.where(~present, -1, np.where(inner[s], number[s],
                                                         np.where(spheres, first_prim[s], first_prim[s] - num_spheres)))
    nodes["count"][at] = np.where(~present | inner[s], 0, np.where(spheres, prims[s], -prims[s]))
    return BVH(nodes, order, max_depth, float(cost[root]))
