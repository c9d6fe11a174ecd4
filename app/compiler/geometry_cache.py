"""Large scenes' compiled geometry kept on disk between runs, beside their BVHs: a scene rendered again
takes its tree and its primitives' rows in the tree's order (triangles, the corners' normals and
texture coordinates, each primitive's shape, material and media) from one entry, where it had
gathered them from its meshes: on a warm start of 870,400 triangles, most of the 0.3-0.5 s its
compile took on the H200's host and on two cores (#55; docs/notes/performance-2026-12.md).

An entry is keyed by the digest of everything the rows are made from (the spheres, their materials
and media; each mesh's vertices, faces, normals, texture coordinates, material and media) and of the
source that makes them (this file, app/compiler/compiled.py, app/scene/media.py, the device's types
and the BVH builder's source), so that a changed scene or compiler never reads an old entry. Only
scenes of at least bvh_cache.MIN_PRIMITIVES primitives are kept, and not those with analytic shapes
or a two-level tree, whose rows are made otherwise, nor an entry over half of MAX_BYTES (about 7
million triangles). Entries are files of pathtrace.io.cache_files (a damaged one is a miss) in the
BVH cache's folder, which PATHTRACE_BVH_CACHE moves or turns off for both; the least recently used
go once these entries exceed MAX_BYTES."""

import hashlib
import os
from pathlib import Path

import numpy as np

from pathtrace.compiler import bvh_cache
from pathtrace.compiler.bvh import BVH
from pathtrace.device.types import BVH_NODE, TRIANGLE
from pathtrace.io import cache_files
from pathtrace.resources import resource_dir

MAX_BYTES = 2 << 30
# an entry's arrays, in its order, each with the type of its rows
ARRAYS = (("nodes", BVH_NODE), ("order", np.dtype(np.int64)), ("spheres", np.dtype((np.float32, 4))),
          ("triangles", TRIANGLE), ("normals", np.dtype((np.float32, 4))), ("uvs", np.dtype((np.float32, 2))),
          ("prim_shape", np.dtype(np.int32)), ("prim_material", np.dtype(np.int32)),
          ("prim_media", np.dtype(np.int32)))
_HEADER = np.dtype([("rows", "<i8", len(ARRAYS)), ("depth", "<i8"), ("cost", "<f8"), ("radius", "<f8"),
                    ("center", "<f8", 3), ("media_per_primitive", "<i8")])

_source_digest = None


def source_digest() -> bytes:
    """The digest of the source that makes an entry's rows and reads it."""
    global _source_digest
    if _source_digest is None:
        here = Path(__file__).resolve()
        h = hashlib.sha256(bvh_cache.builder_digest())
        for path in (here, here.with_name("compiled.py"), here.parent.parent / "scene" / "media.py",
                     here.parent.parent / "device" / "types.py", resource_dir("kernels") / "types.h"):
            h.update(path.read_bytes())
        _source_digest = h.digest()
    return _source_digest


def geometry_digest(scene) -> bytes:
    """A digest of everything a scene's tree and primitive rows are made from: its spheres, their
    materials and media, its meshes' arrays, materials and media, its instances and analytic
    shapes. A CompiledScene holds its scene's (geometry_digest), by which a scene rendered again
    in a process is compiled anew only where it changed (pathtrace.api.prepare), and which keys
    this cache's entries."""
    h = hashlib.sha256()
    arrays = [scene.spheres, scene.sphere_material]
    instances = scene.instances
    if instances is not None:
        arrays += [instances.object, instances.to_world]
    objects = instances.objects if instances is not None else []
    meshes = scene.meshes + [m for o in objects for m in o.meshes]
    for m in meshes:
        arrays += [m.vertices, m.faces, np.zeros(0) if m.normals is None else m.normals,
                   np.zeros(0) if m.uvs is None else m.uvs, np.array([m.material])]
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(str((a.dtype.str, a.shape)).encode())
        h.update(a.data)
    # the media and what bounds them compile with the primitives (pathtrace.compiler.compiled)
    h.update(repr((scene.media, scene.sphere_media, [m.media for m in meshes])).encode())
    # analytic shapes (objects' are copied into scene.shapes)
    h.update(repr([(s.kind, tuple(map(float, s.params)), np.asarray(s.to_world, np.float64).tolist(), s.material,
                    s.flip, s.texture_uv, s.media) for s in scene.shapes]).encode())
    return h.digest()[:16]


def entry_path(compiled) -> Path | None:
    """Where a CompiledScene's entry is, or None where its geometry is not kept (too small, with
    analytic shapes or a two-level tree, or the cache turned off): named by the digest of its
    scene's geometry (geometry_digest), the source and what the compile chose of it."""
    where = bvh_cache.folder()
    if where is None or compiled.scene.shapes or compiled.two_level \
            or compiled.num_spheres + compiled.num_triangles < bvh_cache.MIN_PRIMITIVES:
        return None
    h = hashlib.sha256(source_digest() + compiled.geometry_digest)
    h.update(np.array([compiled.lone_spheres], np.int64).tobytes())
    return where / f"{h.hexdigest()[:32]}.geometry"


def read_entry(path: Path) -> dict | None:
    """The arrays and values stored at path (by the names of ARRAYS, and bvh, radius, center and
    media_per_primitive), or None where there is none or it is damaged."""
    data = cache_files.read_entry(path)      # writable: the rows are used in place, not copied
    if data is None or len(data) < _HEADER.itemsize:
        return None
    header = np.frombuffer(data, _HEADER, count=1)[0]
    rows = header["rows"]
    if np.any(rows < 0) or len(data) != _HEADER.itemsize + sum(int(n) * t.itemsize for n, (_, t) in zip(rows, ARRAYS)):
        return None
    kept, offset = {}, _HEADER.itemsize
    for n, (name, row) in zip(rows, ARRAYS):
        kept[name] = np.frombuffer(data, row, count=int(n), offset=offset)
        offset += int(n) * row.itemsize
    try:
        os.utime(path)      # recently used: removed last
    except OSError:
        pass
    kept["bvh"] = BVH(kept.pop("nodes"), kept.pop("order"), int(header["depth"]), float(header["cost"]))
    kept.update(radius=float(header["radius"]), center=header["center"].astype(np.float32),
                media_per_primitive=bool(header["media_per_primitive"]))
    return kept


def write_soon(path: Path, compiled):
    """Stores a CompiledScene's tree and rows at path in a thread of its own
    (pathtrace.io.cache_files.write_soon): 870,400 triangles' entry is 133 MB, 0.3 s on two cores."""
    arrays = [compiled.bvh.nodes, compiled.bvh.order] + [getattr(compiled, name) for name, _ in ARRAYS[2:]]
    header = np.zeros(1, _HEADER)
    header["rows"] = [len(a) for a in arrays]
    header["depth"], header["cost"] = compiled.bvh.depth, compiled.bvh.cost
    header["radius"], header["center"] = compiled.radius, compiled.center
    header["media_per_primitive"] = compiled.media_per_primitive
    chunks = [np.ascontiguousarray(a, row.base if row.subdtype else row) for a, (_, row) in zip(arrays, ARRAYS)]
    if sum(c.nbytes for c in chunks) > MAX_BYTES // 2:      # would crowd out every other entry
        return
    cache_files.write_soon(path, [header, *chunks], "*.geometry", MAX_BYTES)
