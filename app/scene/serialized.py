"""Mitsuba's `.serialized` mesh files, read as Mitsuba 3 reads them (its src/shapes/serialized.cpp,
whose documentation gives the format): little endian, a header of two uint16s (0x041C and the
version, 3 or 4), then a zlib stream holding a uint32 of flags, in version 4 the shape's name
(NUL-terminated), the vertex and triangle counts (uint64 each), the positions, the normals
(flag 0x0001), the texture coordinates (0x0002) and the vertex colours (0x0008), in float32 or,
with flag 0x2000, float64, and the triangles as uint32 triples. A file may hold several meshes
one after the other, each with its header; the file ends with each mesh's offset (uint64, in
version 3 uint32) and their count (uint32), by which `shape_index` finds its mesh.

As Mitsuba 3 has it: texture coordinates as stored (no v flipped, unlike an OBJ file's `vt`),
vertex colours skipped, and the face-normals flag (0x0010) not read: only the shape's
`face_normals` drops the normals. Every problem is one line naming the element and the file."""

import mmap
import struct
import zlib
from pathlib import Path

import numpy as np

from pathtrace.errors import UserError
from pathtrace.io.files import check_regular_file
from pathtrace.scene.meshes import MAX_FILE_BYTES, MAX_TRIANGLES, MeshData

MAGIC = 0x041C
VERSIONS = (3, 4)
HAS_NORMALS, HAS_UVS, HAS_COLORS, DOUBLE = 0x0001, 0x0002, 0x0008, 0x2000
MAX_NAME = 4096         # bytes of a shape's name
CHUNK = 1 << 20         # compressed bytes fed to zlib at a time
NOT_SERIALIZED = "not a Mitsuba serialized mesh (it does not begin with 0x041C)"


def read_serialized(path: Path, index: int, where: str) -> MeshData:
    """The mesh `index` of the file at path, in its object's space; `where` names the element.
    The file is mapped, not read: a scene's shapes often take their meshes from one large file,
    and each reads only its own mesh's bytes and the dictionary."""
    check_regular_file(path, where, "mesh file", MAX_FILE_BYTES)
    label = f"{where}: {path}"
    try:
        with open(path, "rb") as f:
            if f.seek(0, 2) < 4:             # (an empty file cannot be mapped)
                raise UserError(f"{label}: {NOT_SERIALIZED}")
            with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
                return _read(data, index, label)
    except OSError as e:
        raise UserError(f"{label}: cannot be read ({e.strerror})") from None


def _read(view: mmap.mmap, index: int, label: str) -> MeshData:
    magic, version = struct.unpack_from("<HH", view)
    if magic != MAGIC:
        raise UserError(f"{label}: {NOT_SERIALIZED}")
    if version not in VERSIONS:
        raise UserError(f"{label}: serialized format version {version}; Mitsuba 3 reads versions 3 and 4")
    start = _mesh_offset(view, version, index, label) if index else 0
    return _mesh(_Inflater(view, start + 4), version, label)


def _mesh_offset(view: mmap.mmap, version: int, index: int, label: str) -> int:
    """Where mesh `index` begins, from the dictionary at the file's end."""
    width, size = (8 if version == 4 else 4), len(view)
    count = struct.unpack_from("<I", view, size - 4)[0] if size >= 8 else 0
    if size < 8 + width * count:
        raise UserError(f"{label}: its dictionary of meshes (at the file's end) is damaged: a count of {count} "
                        f"meshes in {size} bytes")
    if not 0 <= index < count:
        raise UserError(f"{label}: shape_index {index} is out of range: the file holds {count} meshes")
    offset = struct.unpack_from("<Q" if width == 8 else "<I", view, size - 4 - width * (count - index))[0]
    if offset + 4 > size or struct.unpack_from("<H", view, offset)[0] != MAGIC:
        raise UserError(f"{label}: the offset of mesh {index} ({offset}) is not the start of a mesh")
    return offset


class _Inflater:
    """The zlib stream that begins at view[start], inflated as far as it is read, its input
    copied a CHUNK at a time (a slice of a mapping is a copy, and holds no export of it)."""

    def __init__(self, view: mmap.mmap, start: int):
        self.view, self.at, self.stream, self.pending, self.kept = view, start, zlib.decompressobj(), b"", b""

    def read(self, n: int) -> bytes:
        """Up to n more bytes of the stream (fewer where it ends)."""
        parts, got = [self.kept[:n]], min(len(self.kept), n)
        self.kept = self.kept[n:]
        while got < n and not self.stream.eof:
            if not self.pending:
                if self.at >= len(self.view):
                    break
                self.pending, self.at = self.view[self.at:self.at + CHUNK], self.at + CHUNK
            piece = self.stream.decompress(self.pending, n - got)
            self.pending = self.stream.unconsumed_tail
            parts.append(piece)
            got += len(piece)
        return b"".join(parts)

    def unread(self, data: bytes):
        self.kept = data + self.kept


def _mesh(stream: _Inflater, version: int, label: str) -> MeshData:
    try:
        head = stream.read(4 + (MAX_NAME + 1 if version == 4 else 0) + 16)
        at = 4
        if version == 4:
            end = head.find(b"\0", at)
            if end < 0:
                raise UserError(f"{label}: the shape's name is not ended (or longer than {MAX_NAME} bytes)")
            at = end + 1
        if len(head) < at + 16:
            raise UserError(f"{label}: the mesh ends within its header")
        stream.unread(head[at + 16:])
        flags, (vertex_count, face_count) = struct.unpack_from("<I", head)[0], struct.unpack_from("<QQ", head, at)
        if not 0 < vertex_count <= 3 * MAX_TRIANGLES:
            raise UserError(f"{label}: a mesh of {vertex_count} vertices: pathtrace takes 1 to {3 * MAX_TRIANGLES}")
        if not 0 < face_count <= MAX_TRIANGLES:
            raise UserError(f"{label}: a mesh of {face_count} triangles: pathtrace takes 1 to {MAX_TRIANGLES}")
        real = np.dtype("<f8" if flags & DOUBLE else "<f4")
        fields = [("vertices", 3), *((("normals", 3),) if flags & HAS_NORMALS else ()),
                  *((("uvs", 2),) if flags & HAS_UVS else ()), *((("colors", 3),) if flags & HAS_COLORS else ())]
        size = sum(vertex_count * width * real.itemsize for _, width in fields) + face_count * 12
        # the arrays as read and as converted to float64 and int64 (a few MB of zlib's stream can
        # claim gigabytes): bounded together
        held = size + sum(vertex_count * width * 8 for name, width in fields if name != "colors") + face_count * 24
        if held > MAX_FILE_BYTES:
            raise UserError(f"{label}: the mesh's arrays would take {held >> 20} MB, more than pathtrace "
                            f"reads ({MAX_FILE_BYTES >> 20} MB)")
        body = stream.read(size)
    except zlib.error as e:
        raise UserError(f"{label}: a damaged serialized mesh (zlib: {e})") from None
    if len(body) < size:
        raise UserError(f"{label}: the mesh ends early: {len(body)} bytes of the {size} that its counts need")
    arrays, at = {}, 0
    for name, width in fields:
        if name != "colors":            # skipped, as Mitsuba 3 skips them
            arrays[name] = np.frombuffer(body, real, vertex_count * width, at).reshape(-1, width).astype(np.float64)
        at += vertex_count * width * real.itemsize
    faces = np.frombuffer(body, "<u4", face_count * 3, at).reshape(-1, 3).astype(np.int64)
    return MeshData(arrays["vertices"], faces, arrays.get("normals"), arrays.get("uvs"))
