"""The two-level BVH of a scene with many instances (app/scene/instances.py): one BVH per object
over its triangles in its own space, one over the scene's own spheres and meshes (drawn by an
instance of the identity), and on top a BVH over the instances' world boxes, whose leaves hold
instances (kernels/bvh.cl: INSTANCES). Its nodes are laid end to end, the top's first, each
tree's child indices moved to where its nodes and primitives landed."""

from dataclasses import dataclass

import numpy as np

from pathtrace.compiler.bvh import BVH
from pathtrace.compiler.bvh_cache import cached_bvh
from pathtrace.errors import UserError
from pathtrace.scene.instances import world_boxes
from pathtrace.device.types import INSTANCE


@dataclass
class TwoLevel:
    bvh: BVH                 # all nodes, the top's first; order: the primitives' (as one BVH's);
                             # depth: the deepest object tree's
    instances: np.ndarray    # INSTANCE rows, in the top tree's order
    lo: np.ndarray           # the instances' world boxes
    hi: np.ndarray


def moved(nodes: np.ndarray, node_base: int, sphere_base: int, triangle_base: int) -> np.ndarray:
    """A tree's nodes with their inner children's indices moved by node_base and their leaves'
    by the first sphere and triangle of the tree's primitives (kernels/types.h: BVHNode)."""
    nodes = nodes.copy()
    index, count = nodes["index"], nodes["count"]
    index[(count == 0) & (index >= 0)] += node_base
    index[count > 0] += sphere_base
    index[count < 0] += triangle_base
    return nodes


def build_two_level(scene, lo: np.ndarray, hi: np.ndarray, mesh_ends: list, meshes: list, queue=None,
                    progress=None) -> TwoLevel:
    """The two-level BVH over the scene's spheres and the triangles of `meshes`, whose boxes are
    lo, hi (spheres first, then each mesh's triangles in turn); meshes[:mesh_ends[0]] are the
    scene's own, meshes[mesh_ends[k]:mesh_ends[k + 1]] object k's."""
    instances = scene.instances
    n_spheres = len(scene.spheres)
    tri_ends = n_spheres + np.cumsum([0] + [len(m.faces) for m in meshes])[mesh_ends]
    # the scene's own shapes, then each object's: one tree each (None for an empty one), the
    # largest built first: where only the cache's trees are asked for (CACHED_ONLY), one it lacks
    # ends the build before the host has built the small ones for nothing
    spans = [(0, int(tri_ends[0]), n_spheres)] + [(int(a), int(b), 0) for a, b in zip(tri_ends[:-1], tri_ends[1:])]
    trees = [None] * len(spans)
    for k in sorted(range(len(spans)), key=lambda k: spans[k][0] - spans[k][1]):
        first, stop, spheres = spans[k]
        if stop > first:
            trees[k] = cached_bvh(lo[first:stop], hi[first:stop], spheres, queue)
    orders = [first + tree.order for (first, _, _), tree in zip(spans, trees) if tree is not None]
    depth = max((tree.depth for tree in trees if tree is not None), default=0)

    # the instances: the scene's own shapes (if any, through the identity: object -1), then the
    # file's, whose objects have triangles
    world_lo, world_hi = world_boxes(instances)
    keep = np.flatnonzero(np.all(world_lo <= world_hi, axis=1))
    own = trees[0] is not None
    obj = np.concatenate([[-1] if own else [], instances.object[keep]]).astype(np.int64)
    if not len(obj):
        raise UserError(f"{scene.source or scene.name}: nothing to render (no shape, and instances of empty objects)")
    to_world = np.concatenate(([np.eye(4)[None]] if own else []) + [instances.to_world[keep]])
    stop = spans[0][1]
    inst_lo = np.concatenate(([lo[:stop].min(axis=0)[None]] if own else []) + [world_lo[keep]])
    inst_hi = np.concatenate(([hi[:stop].max(axis=0)[None]] if own else []) + [world_hi[keep]])
    top = cached_bvh(inst_lo, inst_hi, len(obj), queue, progress)

    # nodes end to end: the top tree, then each object tree, moved to its nodes and primitives
    parts, node_base, roots = [top.nodes], len(top.nodes), []
    sphere_base = triangle_base = 0
    for (first, stop, spheres), tree in zip(spans, trees):
        if tree is None:
            roots.append(-1)
            continue
        roots.append(node_base)
        parts.append(moved(tree.nodes, node_base, sphere_base, triangle_base))
        node_base += len(tree.nodes)
        sphere_base += spheres
        triangle_base += stop - first - spheres
    table = np.zeros(len(obj), INSTANCE)
    ordered = top.order
    m = to_world[ordered]
    table["to_world"] = m[:, :3, :]
    table["to_object"] = np.linalg.inv(m)[:, :3, :]
    table["root"] = np.asarray(roots)[obj[ordered] + 1]        # roots[0]: the scene's own
    # the primitives' order: spheres, then triangles, each kind in its trees' order
    order = np.concatenate(orders)
    order = np.concatenate([order[order < n_spheres], order[order >= n_spheres]])
    return TwoLevel(BVH(np.concatenate(parts), order, depth, top.cost), table, inst_lo, inst_hi)
