"""The light tree: a bounding volume hierarchy over the lights that have a place (area lights,
points and spots), from which next-event estimation picks one light in proportion to its
estimated contribution at the shading point, not its power alone (Conty Estevez and Kulla,
"Importance Sampling of Many Lights with Adaptive Tree Splitting", 2018; pbrt-v4's
BVHLightSampler, section 12.6.3). Each node bounds its lights' positions (a box), their total
power, and their orientations (a cone of normals, axis w and spread theta_o, and the spread
theta_e beyond each normal into which they emit). kernels/light_tree.cl traverses it.

The tree is binary, over the lights' positions on a Morton curve (build_light_tree), built level
by level with NumPy, in O(n log n) for millions of emissive triangles. Each light knows its
leaf and each node its parent, so that the density of a light that a path hits is found by
walking up from its leaf."""

import numpy as np

from pathtrace.device.types import LIGHT_NODE

EMPTY_COS = 2.0      # an empty cone's cos(theta_o): no direction at all


def light_bounds(lo, hi, power, axis, cos_o, cos_e):
    """The leaves' arrays, one row per light: box corners (n, 3), power (n,), cone axis (n, 3),
    cos(theta_o) (n,) and cos(theta_e) (n,)."""
    return dict(lo=np.asarray(lo, np.float64), hi=np.asarray(hi, np.float64), power=np.asarray(power, np.float64),
                axis=np.asarray(axis, np.float64), cos_o=np.asarray(cos_o, np.float64),
                cos_e=np.asarray(cos_e, np.float64))


def primitive_bounds(spheres: np.ndarray, triangles: np.ndarray, prims: np.ndarray, both_sides=None) -> dict:
    """The light bounds of primitives `prims` (of the spheres, then the triangles as (n, 3, 3)
    corners), as area lights: a sphere emits from all its surface, so its normals span every
    direction; a triangle emits from its front, into the hemisphere about its normal (theta_e
    90 degrees), or where both_sides (per prim) is true from both, its normals then spanning
    every direction too (pbrt-v4's LightBounds twoSided, lights.h, bounds the same set of
    directions: the normal and its opposite)."""
    s = spheres[prims[prims < len(spheres)]].astype(np.float64)
    t = triangles[prims[prims >= len(spheres)] - len(spheres)].astype(np.float64)
    normal = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-30)
    sphere_axis = np.tile([0.0, 0.0, 1.0], (len(s), 1))
    cos_o = np.ones(len(t))
    if both_sides is not None:
        cos_o[np.asarray(both_sides)[prims >= len(spheres)]] = -1.0
    return light_bounds(np.concatenate([s[:, :3] - s[:, 3:], t.min(axis=1)]),
                        np.concatenate([s[:, :3] + s[:, 3:], t.max(axis=1)]),
                        np.zeros(len(s) + len(t)), np.concatenate([sphere_axis, normal]),
                        np.concatenate([np.full(len(s), -1.0), cos_o]), np.zeros(len(s) + len(t)))


def morton_codes(centres: np.ndarray) -> np.ndarray:
    """30-bit Morton (Z-order) codes of points over their bounding box: 10 bits an axis."""
    lo, hi = centres.min(axis=0), centres.max(axis=0)
    cells = np.clip((centres - lo) / np.maximum(hi - lo, 1e-30) * 1023, 0, 1023).astype(np.uint64)

    def spread(v):     # 10 bits to every third of 30
        v = (v | (v << 16)) & 0x030000FF
        v = (v | (v << 8)) & 0x0300F00F
        v = (v | (v << 4)) & 0x030C30C3
        return (v | (v << 2)) & 0x09249249
    return (spread(cells[:, 0]) << np.uint64(2)) | (spread(cells[:, 1]) << np.uint64(1)) | spread(cells[:, 2])


def union_cones(wa, ca, wb, cb):
    """The smallest cone (axis, cos spread) holding cones a and b, row by row (pbrt-v4's
    DirectionCone Union): an empty cone (cos EMPTY_COS) adds nothing."""
    ta, tb = np.arccos(np.clip(ca, -1, 1)), np.arccos(np.clip(cb, -1, 1))
    td = np.arccos(np.clip(np.einsum("ij,ij->i", wa, wb), -1, 1))
    theta = (ta + td + tb) / 2
    # rotate a's axis towards b's by theta - theta_a, about their common normal (Rodrigues)
    k = np.cross(wa, wb)
    norm = np.linalg.norm(k, axis=1, keepdims=True)
    k = k / np.maximum(norm, 1e-30)
    angle = (theta - ta)[:, None]
    w = wa * np.cos(angle) + np.cross(k, wa) * np.sin(angle) + k * np.einsum("ij,ij->i", k, wa)[:, None] * (1 - np.cos(angle))
    cos = np.cos(theta)
    whole = (theta >= np.pi) | (norm[:, 0] < 1e-12)
    w, cos = np.where(whole[:, None], wa, w), np.where(whole, -1.0, cos)
    a_holds = np.minimum(td + tb, np.pi) <= ta
    b_holds = np.minimum(td + ta, np.pi) <= tb
    w, cos = np.where(b_holds[:, None], wb, w), np.where(b_holds, cb, cos)
    w, cos = np.where(a_holds[:, None], wa, w), np.where(a_holds, ca, cos)
    w, cos = np.where((cb > 1)[:, None], wa, w), np.where(cb > 1, ca, cos)
    w, cos = np.where((ca > 1)[:, None], wb, w), np.where(ca > 1, cb, cos)
    return w, cos


def build_light_tree(bounds: dict) -> tuple:
    """(LIGHT_NODE array, the leaf node of each light): a binary radix tree over the lights'
    Morton codes (Karras, "Maximizing Parallelism in the Construction of BVHs, Octrees, and k-d
    Trees", 2012), so that each node is a cell of the Morton grid and bounds lights that lie
    together; lights in one cell are halved by count. Built top-down one level at a time, every
    node of a level at once; nodes are numbered level by level, a node's two children
    consecutive."""
    n = len(bounds["power"])
    centres = (bounds["lo"] + bounds["hi"]) / 2
    codes = morton_codes(centres)
    order = np.argsort(codes, kind="stable")
    codes = codes[order]
    start, end = np.array([0]), np.array([n])
    parent = np.array([-1])
    levels = []          # per level: (first node index, start, end, parent); at most 30 levels
                         # of Morton bits and log2(n) of halving (kernels/light_tree.cl allows 64)
    count = 0
    while len(start):
        levels.append((count, start, end, parent))
        count += len(start)
        inner = end - start > 1
        s, e, ids = start[inner], end[inner], count - len(start) + np.flatnonzero(inner)
        differ = codes[s] ^ codes[e - 1]
        top = np.zeros(len(s), np.int64)
        top[differ > 0] = np.floor(np.log2(differ[differ > 0].astype(np.float64))).astype(np.int64)
        prefix = ((codes[s] >> top.astype(np.uint64)) | np.uint64(1)) << top.astype(np.uint64)
        split = np.where(differ > 0, np.searchsorted(codes, prefix), (s + e) // 2)
        start = np.stack([s, split], 1).ravel()
        end = np.stack([split, e], 1).ravel()
        parent = np.repeat(ids, 2)
    nodes = np.zeros(count, LIGHT_NODE)
    lo, hi = np.zeros((count, 3)), np.zeros((count, 3))
    power, axis = np.zeros(count), np.zeros((count, 3))
    cos_o, cos_e = np.zeros(count), np.zeros(count)
    nodes["child"] = -1
    leaf = np.empty(n, np.int64)
    for first, start, end, parent in reversed(levels):
        ids = first + np.arange(len(start))
        nodes["parent"][ids] = parent
        is_leaf = end - start == 1
        light = order[start[is_leaf]]
        at = ids[is_leaf]
        leaf[light] = at
        lo[at], hi[at], power[at] = bounds["lo"][light], bounds["hi"][light], bounds["power"][light]
        axis[at], cos_o[at], cos_e[at] = bounds["axis"][light], bounds["cos_o"][light], bounds["cos_e"][light]
        at = ids[~is_leaf]
        if len(at):
            # the children of this level's inner nodes are the next level's nodes, in order
            child = first + len(start) + 2 * np.arange(len(at))
            nodes["child"][at] = child
            a, b = child, child + 1
            lo[at], hi[at] = np.minimum(lo[a], lo[b]), np.maximum(hi[a], hi[b])
            power[at] = power[a] + power[b]
            axis[at], cos_o[at] = union_cones(axis[a], np.where(power[a] > 0, cos_o[a], EMPTY_COS),
                                              axis[b], np.where(power[b] > 0, cos_o[b], EMPTY_COS))
            cos_e[at] = np.minimum(cos_e[a], cos_e[b])
    nodes["lo"][:, :3], nodes["lo"][:, 3] = lo, power
    nodes["hi"][:, :3], nodes["hi"][:, 3] = hi, np.minimum(cos_o, 1.0)
    nodes["axis"][:, :3], nodes["axis"][:, 3] = axis, cos_e
    return nodes, leaf
