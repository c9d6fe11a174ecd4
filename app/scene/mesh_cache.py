"""The OBJ files' meshes of a scene, kept beside its entry in the scene cache
(pathtrace.scene.read_cache), for the scene's next read after its file changed: a camera moved
or a material edited, the scene is read again whole, but each of its unchanged OBJ files is then
taken from there rather than parsed again (on two cores, 850 OBJ files of 77 KB: docs/notes/
performance-2026-12.md, 2026-12-03, thirty-first session).

A scene's reading runs within `reading(kept)`: the meshes of its entry, by their files' stamps
(pathtrace.io.files.stamp: absolute path, size, time of last change), are looked up (`kept`),
and every OBJ file's mesh read meanwhile, in this process or in those that read for it
(pathtrace.scene.mesh_processes), is collected for the next entry. The readings under way are
one list for the process's threads (those of MeshFiles read for a scene's reading too): two
scenes read at once each collect the other's meshes as well, which costs their entries space,
not a wrong mesh, a mesh being kept by its file's stamp. A mesh is kept as read_mesh
returns it, checked, where its check reported nothing: a file with warnings (degenerate
triangles dropped) is parsed on each read, so that they name the field referring to it each
time. They are kept in one file per scene, beside its entry, not in one per mesh file: creating
hundreds of files had cost a new scene's start more than the parses it saves a later one."""

import threading
from contextlib import contextmanager

_lock = threading.Lock()
_readings = []           # the (kept, found) of the readings under way, in any thread


@contextmanager
def reading(kept: dict):
    """Within it, the meshes of `kept` ({stamp: mesh}) are looked up, and those read are collected
    into the dict it yields."""
    found = {}
    mine = (kept, found)
    with _lock:
        _readings.append(mine)
    try:
        yield found
    finally:
        with _lock:
            _readings[:] = [r for r in _readings if r is not mine]


def holds(at: tuple) -> bool:
    """Whether a reading under way has the mesh kept of the file of stamp `at`."""
    with _lock:
        return any(at in kept for kept, _ in _readings)


def lookup(at: tuple):
    """The mesh kept of the file of stamp `at` (collected again for the next entries), or None."""
    with _lock:
        mesh = next((kept[at] for kept, _ in _readings if at in kept), None)
    if mesh is not None:
        collect(at, mesh)
    return mesh


def collect(at: tuple, mesh):
    """A mesh read from the file of stamp `at`, for the entry of the scene being read."""
    with _lock:
        for _, found in _readings:
            found[at] = mesh
