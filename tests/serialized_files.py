"""Mitsuba `.serialized` mesh files written for the tests, by the layout Mitsuba 3's
src/shapes/serialized.cpp documents (app/scene/serialized.py reads them). Mitsuba 3 itself reads
the fixtures of tests/scenes/serialized.xml for its reference image (scripts/make_references.py),
so that the writer and the reader are not only each other's check.

    python -m tests.serialized_files     # writes tests/scenes/*.serialized again
"""

import struct
import zlib
from pathlib import Path

import numpy as np

SCENES = Path(__file__).parent / "scenes"


def mesh_stream(vertices, faces, normals=None, uvs=None, colors=None, name="mesh", version=4, double=False,
                flags=0) -> bytes:
    """One mesh: its header, then its zlib stream."""
    real = "<f8" if double else "<f4"
    flags |= (0x2000 if double else 0x1000) | (0x0001 if normals is not None else 0) \
        | (0x0002 if uvs is not None else 0) | (0x0008 if colors is not None else 0)
    body = struct.pack("<I", flags) + (name.encode() + b"\0" if version == 4 else b"")
    body += struct.pack("<QQ", len(vertices), len(faces))
    for array in (vertices, normals, uvs, colors):
        if array is not None:
            body += np.asarray(array, real).tobytes()
    body += np.asarray(faces, "<u4").tobytes()
    return struct.pack("<HH", 0x041C, version) + zlib.compress(body)


def serialized_file(meshes, version=4) -> bytes:
    """The streams of `meshes` (each mesh_stream's bytes) and the dictionary of their offsets."""
    data, offsets = b"", []
    for mesh in meshes:
        offsets.append(len(data))
        data += mesh
    width = "<Q" if version == 4 else "<I"
    return data + b"".join(struct.pack(width, o) for o in offsets) + struct.pack("<I", len(meshes))


def write_fixtures():
    """tests/scenes/meshes.serialized (version 4, float32): the torus of torus.ply with its uvs
    and smooth normals, then the octahedron of octahedron.obj without normals but with vertex
    colours (which Mitsuba skips); and tests/scenes/double.serialized (version 3, float64): the
    octahedron, then the torus without normals or uvs."""
    from pathtrace.scene.meshes import read_mesh, vertex_normals
    torus = read_mesh(SCENES / "torus.ply", "torus")
    octahedron = read_mesh(SCENES / "octahedron.obj", "octahedron")
    colors = np.linspace(0, 1, 3 * len(octahedron.vertices)).reshape(-1, 3)
    (SCENES / "meshes.serialized").write_bytes(serialized_file([
        mesh_stream(torus.vertices, torus.faces, vertex_normals(torus.vertices, torus.faces), torus.uvs, name="torus"),
        mesh_stream(octahedron.vertices, octahedron.faces, colors=colors, name="octahedron")]))
    (SCENES / "double.serialized").write_bytes(serialized_file([
        mesh_stream(octahedron.vertices, octahedron.faces, version=3, double=True),
        mesh_stream(torus.vertices, torus.faces, version=3, double=True)], version=3))


if __name__ == "__main__":
    write_fixtures()
