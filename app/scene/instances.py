"""Instancing: a group of meshes defined once in a space of its own (pbrt-v4's ObjectBegin,
Mitsuba 3's shapegroup) and drawn many times, each instance through its own transform
(ObjectInstance, instance). The compiled scene either copies each instance's meshes into world
space (flattening, for scenes of few instanced triangles, whose one-level BVH traces fastest) or
builds one BVH per object and a BVH over the instances' world boxes, whose traversal turns each
ray into an instance's object space (a two-level BVH: app/compiler/two_level.py, kernels/bvh.cl), so that
memory grows with the objects' triangles and the number of instances, not their product."""

from dataclasses import dataclass, field, replace

import numpy as np

from pathtrace.scene import transform
from pathtrace.scene.meshes import MAX_COORDINATE

# Scenes whose instances hold at most this many triangles in all are flattened: below it the
# copies cost little memory, and a one-level BVH saves every ray the transforms.
FLATTEN_MAX = 1 << 20


@dataclass
class SceneObject:
    """A named group of meshes (vertices in the object's space) that instances draw, and of
    analytic shapes (pathtrace.shapes.Shape, in the object's space), which
    SceneBuilder.add_instance copies into the world at each instance."""
    name: str
    meshes: list = field(default_factory=list)
    shapes: list = field(default_factory=list)

    @property
    def triangle_count(self) -> int:
        return sum(len(m.faces) for m in self.meshes)


@dataclass
class Instances:
    """The scene's instances: per instance, its object (a row of `objects`) and its
    world-from-object transform."""
    objects: list                                                  # SceneObject
    object: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))             # (N,)
    to_world: np.ndarray = field(default_factory=lambda: np.zeros((0, 4, 4)))            # (N, 4, 4)

    def __len__(self):
        return len(self.object)

    @property
    def triangle_count(self) -> int:
        """The triangles the instances draw in all (as many as flattening would copy)."""
        counts = np.array([o.triangle_count for o in self.objects] + [0], np.int64)
        return int(counts[self.object].sum()) if len(self.object) else 0


# the least |determinant| of an instance's linear part: the traversal carries rays into the
# object by the transform's inverse, stored in float32 (app/compiler/two_level.py, to_object), whose
# entries grow as the determinant shrinks
MIN_DETERMINANT = 1e-30


def determinant(m: np.ndarray) -> float:
    """The determinant of a 4x4 transform's 3x3 part, in Python floats: a reader calls it per
    instance, where NumPy's det costs 10 times as much."""
    (a, b, c, _), (d, e, f, _), (g, h, i, _) = m[:3].tolist()
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def near_singular(m: np.ndarray) -> bool:
    """Whether a 4x4 world-from-object transform is too near singular for an instance (NaN
    included)."""
    return not abs(determinant(m)) >= MIN_DETERMINANT


def check_instances(instances: Instances, materials) -> str | None:
    """A problem with the instances, or None: each object one of `objects`, none of its meshes
    emitting (the readers make them so; the API may not), each transform finite, affine and
    invertible, and each instance within the coordinates float32 can trace."""
    m = instances.to_world
    if np.any((instances.object < 0) | (instances.object >= len(instances.objects))):
        return "an instance of an object that does not exist"
    emission = materials.rows["emission"][:, :3]
    for mesh in (mesh for o in instances.objects for mesh in o.meshes):
        if np.any(emission[mesh.material] > 0):
            return (f"mesh '{mesh.name}' of an instanced object emits; instances have no area lights "
                    "(as in pbrt-v4 and Mitsuba 3)")
    bad = ~np.all(np.isfinite(m), axis=(1, 2)) | np.any(m[:, 3] != (0, 0, 0, 1), axis=1)
    bad[~bad] = np.abs(np.linalg.det(m[~bad, :3, :3])) < MIN_DETERMINANT
    if np.any(bad):
        return f"instance {int(np.argmax(bad))}: its transform is not finite, affine and invertible"
    lo, hi = world_boxes(instances)
    with np.errstate(over="ignore", invalid="ignore"):
        far = ~(np.maximum(np.abs(lo), np.abs(hi)).max(axis=1) <= MAX_COORDINATE) & np.all(lo <= hi, axis=1)
    if np.any(far):
        return f"instance {int(np.argmax(far))} reaches beyond {MAX_COORDINATE:g}, which float32 cannot trace"
    return None


def object_box(obj: SceneObject) -> tuple:
    """The box (lo, hi) of an object's triangles; empty (lo > hi) where it has none."""
    corners = [m.vertices[m.faces].reshape(-1, 3) for m in obj.meshes if len(m.faces)]
    if not corners:
        return np.full(3, np.inf), np.full(3, -np.inf)
    c = np.concatenate(corners)
    return c.min(axis=0).astype(np.float64), c.max(axis=0).astype(np.float64)


def world_boxes(instances: Instances) -> tuple:
    """Each instance's world box (lo, hi): its object's box's corners moved by its transform;
    empty (lo > hi) for an instance of an object without triangles."""
    boxes = np.array([object_box(o) for o in instances.objects]).reshape(-1, 2, 3)
    lo, hi = boxes[instances.object, 0], boxes[instances.object, 1]
    empty = ~np.all(lo <= hi, axis=1)
    lo, hi = np.where(empty[:, None], 0.0, lo), np.where(empty[:, None], 0.0, hi)
    pick = np.array([[(k >> a) & 1 for a in range(3)] for k in range(8)], bool)
    corners = np.where(pick[None], hi[:, None, :], lo[:, None, :])           # (N, 8, 3)
    m = instances.to_world
    with np.errstate(over="ignore", invalid="ignore"):
        world = np.einsum("nij,nkj->nki", m[:, :3, :3], corners) + m[:, None, :3, 3]
    lo, hi = world.min(axis=1), world.max(axis=1)
    lo[empty], hi[empty] = np.inf, -np.inf
    return lo, hi


def flattened_meshes(instances: Instances) -> list:
    """Each instance's meshes in world space: vertices and normals transformed, and the faces
    turned round where the transform swaps handedness, so that fronts stay fronts."""
    out = []
    for k in range(len(instances)):
        m = instances.to_world[k]
        flip = transform.flips_handedness(m)
        for mesh in instances.objects[instances.object[k]].meshes:
            normals = None if mesh.normals is None else transform.transform_normals(m, mesh.normals).astype(np.float32)
            out.append(replace(mesh, vertices=transform.transform_points(m, mesh.vertices).astype(np.float32),
                               faces=mesh.faces[:, ::-1] if flip else mesh.faces, normals=normals))
    return out
