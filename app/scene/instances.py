"""Instancing: a group of meshes defined once in a space of its own (pbrt-v4's ObjectBegin,
Mitsuba 3's shapegroup) and drawn many times, each instance through its own transform
(ObjectInstance, instance). The compiled scene either copies each instance's meshes into world
space (flattening, for scenes of few instanced triangles, whose one-level BVH traces fastest) or
builds one BVH per object and a BVH over the instances' world boxes, whose traversal turns each
ray into an instance's object space (a two-level BVH: app/two_level.py, kernels/bvh.cl), so that
memory grows with the objects' triangles and the number of instances, not their product."""

from dataclasses import dataclass, field, replace

import numpy as np

from pathtrace.scene import transform

# Scenes whose instances hold at most this many triangles in all are flattened: below it the
# copies cost little memory, and a one-level BVH saves every ray the transforms.
FLATTEN_MAX = 1 << 20


@dataclass
class SceneObject:
    """A named group of meshes (vertices in the object's space) that instances draw."""
    name: str
    meshes: list = field(default_factory=list)

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


def check_instances(instances: Instances) -> str | None:
    """A problem with the instances, or None: each transform finite, affine and invertible, and
    each object one of `objects` (the readers make them so; the API may not)."""
    m = instances.to_world
    if np.any((instances.object < 0) | (instances.object >= len(instances.objects))):
        return "an instance of an object that does not exist"
    bad = ~np.all(np.isfinite(m), axis=(1, 2)) | np.any(m[:, 3] != (0, 0, 0, 1), axis=1)
    bad[~bad] = np.abs(np.linalg.det(m[~bad, :3, :3])) < 1e-30
    if np.any(bad):
        return f"instance {int(np.argmax(bad))}: its transform is not finite, affine and invertible"
    return None


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
