"""Scenes read from files kept on disk between runs, as their BVHs and kernels are: a scene opened
again is one file's read, not its meshes' parsing (850 OBJ files were most of the 10.5 s a warm
start took on the H200; #55).

An entry holds the scene as read (pickled), the warnings its reading gave, which are told again
when it is used, and a stamp (path, size, time of last change) of every file the reading checked
(pathtrace.io.files.check_regular_file: the scene file, its includes, meshes, images). It is used
only while every stamp still holds. Beside it, a file of the meshes of the scene's OBJ files
(pathtrace.scene.mesh_cache) gives them to the scene's next read where the entry no longer
holds. It is keyed by the scene file's absolute path (a built-in
scene's name) and by the digest of pathtrace's Python source, so that a changed reader never
reads an old entry. Scenes read in less than MIN_SECONDS are not kept. Entries are files of
pathtrace.io.cache_files (a damaged one is a miss); the least recently used go once they exceed
MAX_BYTES. The folder is cache_dir()/scenes, or the one PATHTRACE_SCENE_CACHE names;
PATHTRACE_SCENE_CACHE=0 turns the cache off."""

import hashlib
import io
import os
import pickle
import time
from pathlib import Path

import numpy as np

from pathtrace.io import cache_files
from pathtrace.errors import held_warnings, warn
from pathtrace.io.files import noting_files, stamp
from pathtrace.scene import mesh_cache

MIN_SECONDS = 0.1
MAX_BYTES = 2 << 30         # of scenes, and again of the meshes kept beside them
MESHES = ".meshes"          # the suffix of those meshes' files
_source_digest = None


def source_digest() -> bytes:
    """The digest of every Python file of pathtrace: what reads scenes and the types they hold."""
    global _source_digest
    if _source_digest is None:
        package = Path(__file__).resolve().parent.parent
        h = hashlib.sha256()
        for path in sorted(package.rglob("*.py")):
            h.update(str(path.relative_to(package)).encode())
            h.update(path.read_bytes())
        _source_digest = h.digest()
    return _source_digest


def folder():
    """The cache's folder, or None where it is turned off."""
    return cache_files.chosen_folder("PATHTRACE_SCENE_CACHE", "scenes")


def entry_path(where: Path, name: str) -> Path:
    """A file's entry is the file's by the name it is given as, too: what was read holds paths
    as given (the scene's source, its meshes' files, its warnings), which the same file named
    otherwise, or from another folder, would tell wrongly."""
    path = Path(name)
    try:
        key = f"file:{path.resolve()} as {name}" if path.is_file() else f"built-in:{name}"
    except (OSError, ValueError):         # a name no file can have: the reader says what is wrong
        key = f"built-in:{name}"
    return where / f"{hashlib.sha256(source_digest() + key.encode()).hexdigest()[:32]}.scene"


def cached_read(name: str, read):
    """read(name)'s scene, from the cache where an entry for it holds; a scene read slowly is
    stored there, with the meshes of its OBJ files (pathtrace.scene.mesh_cache), which a read
    after a change of the scene's file takes from its stale entry. Within grouped_warnings(), as
    load_scene calls it."""
    where = folder()
    if where is None:
        return read(name)
    path = entry_path(where, name)
    kept, meshes = _read_entry(path)
    if kept is not None:
        notes, scene = kept
        for note in notes:
            warn(note)
        return scene
    before = len(held_warnings())
    start = time.perf_counter()
    with noting_files() as files, mesh_cache.reading(meshes) as found:
        scene = read(name)
    if time.perf_counter() - start >= MIN_SECONDS:
        _write_entry(path, files, held_warnings()[before:], scene, found)
    return scene


def _read_entry(path: Path):
    """((warnings, scene), {}) of the entry at path; where there is none, it is damaged, or a file
    it was read from has changed or gone since, (None, the meshes kept beside it)."""
    data = cache_files.read_entry(path)
    try:
        if data is None:
            return None, _kept_meshes(path)
        with io.BytesIO(data) as f:
            stamps, notes = pickle.load(f)
            for name, size, changed in stamps:
                try:
                    holds = stamp(name, os.stat(name)) == (name, size, changed)
                except OSError:
                    holds = False
                if not holds:
                    return None, _kept_meshes(path)
            scene = pickle.load(f)
    except (ValueError, EOFError, pickle.UnpicklingError, AttributeError, ImportError, TypeError):
        return None, {}        # an entry this pathtrace cannot read: a miss
    for used in (path, path.with_suffix(MESHES)):
        try:
            os.utime(used)     # recently used: removed last
        except OSError:
            pass
    return (notes, scene), {}


ALIGNMENT = 64       # of the meshes' arrays in their file, as NumPy's own allocations are aligned


def _kept_meshes(path: Path) -> dict:
    """The meshes kept beside the entry at path ({stamp: mesh}, pathtrace.scene.mesh_cache), {}
    where there are none or they are damaged. A file of their own, so that a scene read from its
    entry reads none of them: its pickle's arrays are views of the file's bytes, read whole."""
    data = cache_files.read_entry(path.with_suffix(MESHES))
    if data is None:
        return {}
    try:
        size, count = int.from_bytes(data[:8], "little"), int.from_bytes(data[8:16], "little")
        index = np.frombuffer(data, np.uint64, 2 * count, 16 + size).reshape(-1, 2)
        arrays = [data[int(start):int(start) + int(n)] for start, n in index]
        return pickle.loads(data[16:16 + size], buffers=arrays)
    except Exception:        # whatever a file that passed its checksum but not this pathtrace's reading holds
        return {}


def _write_meshes(path: Path, meshes: dict):
    """Stores the meshes at path in a thread of their own (pathtrace.io.cache_files.write_soon),
    their arrays written as they are (pickle's buffers out of band), each at an ALIGNMENT in the
    file: a new scene's first image does not wait for 50 MB of an 850-mesh scene's being copied
    and written. Meshes of more than half of MAX_BYTES are not kept: they would crowd out every
    other scene's."""
    arrays = []
    head = pickle.dumps(meshes, protocol=5, buffer_callback=arrays.append)
    views = [a.raw() for a in arrays]
    if sum(v.nbytes for v in views) > MAX_BYTES // 2:
        return
    index = np.zeros((len(views), 2), np.uint64)
    position = 16 + len(head) + index.nbytes       # in the payload, which follows the checksum
    chunks = [len(head).to_bytes(8, "little"), len(views).to_bytes(8, "little"), head, index]
    for k, v in enumerate(views):
        pad = -(cache_files.CHECKSUM_BYTES + position) % ALIGNMENT
        index[k] = position + pad, v.nbytes
        chunks += [bytes(pad), v]
        position += pad + v.nbytes
    cache_files.write_soon(path, chunks, "*" + MESHES, MAX_BYTES)


def _write_entry(path: Path, files: list, notes: list, scene, meshes: dict):
    """Stores the scene and, beside it, its OBJ files' meshes (each whole or not at all), and
    removes the oldest entries beyond MAX_BYTES. A scene that cannot be pickled (one holding
    objects made in Python by the user) is not kept."""
    try:
        head = pickle.dumps((sorted(set(files)), notes), protocol=pickle.HIGHEST_PROTOCOL)
        body = pickle.dumps(scene, protocol=pickle.HIGHEST_PROTOCOL)
    except (pickle.PicklingError, TypeError, AttributeError):
        return
    if meshes:
        _write_meshes(path.with_suffix(MESHES), meshes)
    if cache_files.write_entry(path, head, body):
        cache_files.prune(path.parent, "*.scene", MAX_BYTES)
