"""BVHs of large scenes kept on disk between runs, as the kernels are: a scene rendered or viewed
again skips its build, the longest step of loading a large mesh (about 1 s of the 2.5 s from
command to first image for a million triangles on two CPU cores; docs/benchmarks.md, Loading).

An entry is keyed by the digest of what the tree is built from, the primitives' boxes and where
the spheres end, together with the source of the builder (app/compiler/bvh.py and kernels/build/) and of
this file, so that a changed builder or entry format never reads an old entry. Any device's tree serves every device: each is a
valid BVH over the same boxes. Entries are files of pathtrace.io.cache_files (a damaged one is built
again and replaced), and the least recently used are removed once the entries exceed MAX_BYTES.
Scenes of fewer than MIN_PRIMITIVES primitives build in a fraction of a second and are not
cached; those of at most HOST_MAX are built on the host (app/compiler/host_bvh.py). The folder is
cache_dir()/bvh, or the folder that PATHTRACE_BVH_CACHE names; PATHTRACE_BVH_CACHE=0 turns the
cache off."""

import hashlib
import os
from pathlib import Path

import numpy as np

from pathtrace.io import cache_files
from pathtrace.compiler.bvh import BVH, build_bvh
from pathtrace.compiler.host_bvh import build_on_host
from pathtrace.resources import resource_dir
from pathtrace.device.types import BVH_NODE

# a queue for cached_bvh that builds nothing: a tree not in the cache raises NotCached
CACHED_ONLY = "cached only"
MIN_PRIMITIVES = 16384      # where a build takes 0.07 s on two cores (64,000 spheres: 0.30 s; a read: < 0.01 s)
# trees of at most this many primitives are built on the host, in about what a warm device build
# takes on two quiet cores (4,096: 0.06 s; 16,383: 0.19 s)
HOST_MAX = 4096
MAX_BYTES = 1 << 30
_HEADER = np.dtype([("nodes", "<i8"), ("primitives", "<i8"), ("depth", "<i8"), ("cost", "<f8")])

_builder_digest = None


def builder_digest() -> bytes:
    """The digest of the builder's source (app/compiler/bvh.py and its kernels) and of this file's, which
    writes and reads the entries."""
    global _builder_digest
    if _builder_digest is None:
        h = hashlib.sha256(Path(__file__).read_bytes())
        h.update(Path(__file__).with_name("bvh.py").read_bytes())
        for name in ("types.h", "build/morton.cl", "build/ploc.cl", "build/collapse.cl"):
            h.update((resource_dir("kernels") / name).read_bytes())
        _builder_digest = h.digest()
    return _builder_digest


def folder():
    """The cache's folder, or None where it is turned off."""
    return cache_files.chosen_folder("PATHTRACE_BVH_CACHE", "bvh")


def entry_key(lo: np.ndarray, hi: np.ndarray, num_spheres: int) -> str:
    h = hashlib.sha256(builder_digest())
    h.update(np.array([len(lo), num_spheres], np.int64).tobytes())
    h.update(np.ascontiguousarray(lo, np.float32))
    h.update(np.ascontiguousarray(hi, np.float32))
    return h.hexdigest()[:32]


class NotCached(Exception):
    """cached_bvh's answer, with the queue CACHED_ONLY, for a tree the cache does not hold."""


def cached_bvh(lo: np.ndarray, hi: np.ndarray, num_spheres: int = None, queue=None, progress=None) -> BVH:
    """build_bvh's tree (same arguments), read from the cache where an entry holds it; a tree
    built is stored there. With the queue CACHED_ONLY, a tree the cache does not hold raises
    NotCached. A tree of at most HOST_MAX primitives is built on the host, with no device
    (pathtrace.compiler.host_bvh), and none of fewer than MIN_PRIMITIVES is stored."""
    n, where = len(lo), folder()
    if n <= HOST_MAX:
        return build_on_host(lo, hi, num_spheres, progress)
    if n < MIN_PRIMITIVES or where is None:
        if queue is CACHED_ONLY:
            raise NotCached
        return build_bvh(lo, hi, num_spheres, queue, progress)
    path = where / f"{entry_key(lo, hi, n if num_spheres is None else num_spheres)}.bvh"
    bvh = read_entry(path, n)
    if bvh is not None:
        if progress:
            progress(1.0)
        return bvh
    if queue is CACHED_ONLY:
        raise NotCached
    bvh = build_bvh(lo, hi, num_spheres, queue, progress)
    write_entry(path, bvh)
    return bvh


def read_entry(path: Path, primitives: int):
    """The BVH stored at path, or None where there is none, or it is damaged or not for this
    many primitives."""
    data = cache_files.read_entry(path)      # writable: the nodes are used in place, not copied
    if data is None or len(data) < _HEADER.itemsize:
        return None
    header = np.frombuffer(data, _HEADER, count=1)[0]
    count = int(header["nodes"])
    if int(header["primitives"]) != primitives or count < 1 \
            or len(data) != _HEADER.itemsize + count * BVH_NODE.itemsize + primitives * 4:
        return None
    nodes = np.frombuffer(data, BVH_NODE, count=count, offset=_HEADER.itemsize)
    order = np.frombuffer(data, np.int32, count=primitives, offset=_HEADER.itemsize + nodes.nbytes)
    try:
        os.utime(path)      # recently used: removed last
    except OSError:
        pass
    return BVH(nodes, order.astype(np.int64), int(header["depth"]), float(header["cost"]))


def write_entry(path: Path, bvh: BVH):
    """Stores bvh at path (pathtrace.io.cache_files: whole or not at all), then removes the oldest
    entries beyond MAX_BYTES."""
    header = np.zeros(1, _HEADER)
    header["nodes"], header["primitives"], header["depth"], header["cost"] = \
        len(bvh.nodes), len(bvh.order), bvh.depth, bvh.cost
    if cache_files.write_entry(path, header, np.ascontiguousarray(bvh.nodes), bvh.order.astype(np.int32)):
        cache_files.prune(path.parent, "*.bvh", MAX_BYTES)
