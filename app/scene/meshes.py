"""Reading triangle meshes: PLY through NumPy (plyfile for what its fast path does not take),
OBJ through NumPy (pathtrace.scene.obj), STL, glTF and GLB through trimesh. Every problem is one
line naming the file; degenerate triangles are dropped with a warning.

Texture coordinates follow Mitsuba 3's convention, v = 0 at an image's top row: a PLY file's
(u, v) as they are (Mitsuba reads them so); OBJ's vt and glTF's TEXCOORD_0 as Mitsuba's OBJ
reader and the glTF format place them (trimesh gives both with v = 0 at the bottom: flipped)."""

import gzip
import io
import os
import threading
import warnings
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path
from typing import NamedTuple

import numpy as np

from pathtrace.errors import UserError, warn
from pathtrace.io.files import check_regular_file, stamp
from pathtrace.scene import mesh_cache
from pathtrace.scene.transform import flips_handedness, transform_normals, transform_points

FORMATS = (".ply", ".ply.gz", ".obj", ".stl", ".gltf", ".glb")
MAX_FILE_BYTES = 4 << 30            # a mesh file larger than this is refused before reading
MAX_TRIANGLES = 64_000_000          # ~6 GB of device memory (docs/performance.md)
# the largest coordinate a shape may reach: the BVH's float32 surface areas, (2 x)^2, stay finite
MAX_COORDINATE = 1e18


# set where a scene being read names LARGE_SCENE_BYTES of mesh files or more (MeshFiles.add): a tree
# of more primitives than the host builds, which a new scene builds on a device, whose builder's
# kernels a devices' opening then compiles beside the reading (pathtrace.compiler.builder.tree_likely);
# cleared as devices begin to open for the next scene (tree_unknown)
large_scene_named = threading.Event()
LARGE_SCENE_BYTES = 512 << 10


class MeshData(NamedTuple):
    vertices: np.ndarray          # (V, 3) float64
    faces: np.ndarray             # (F, 3) int64
    normals: np.ndarray | None    # (V, 3), or None
    uvs: np.ndarray | None = None  # (V, 2), or None


# PLY vertex properties that hold texture coordinates, as Mitsuba 3 and pbrt-v4 accept them
PLY_UV_NAMES = (("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t"))


def read_mesh(path: Path, where: str, warn=warn, degenerate=None) -> MeshData:
    """A mesh file's vertices, faces, normals and texture coordinates. `where` names the field
    that refers to the file, for messages; `warn` takes the warning lines; `degenerate` is
    check_mesh's."""
    path = Path(path)
    suffix = ".ply.gz" if path.name.lower().endswith(".ply.gz") else path.suffix.lower()
    if suffix not in FORMATS:
        raise UserError(f"{where}: {path}: unknown mesh format '{path.suffix}' "
                        f"(use {', '.join(FORMATS)})")
    checked_at = check_regular_file(path, where, "mesh file", MAX_FILE_BYTES)
    kept_as = checked_at if suffix == ".obj" else None       # OBJ meshes are kept (mesh_cache)
    kept = None if kept_as is None else mesh_cache.lookup(kept_as)
    if kept is not None:
        return kept
    notes = []               # the parser's warnings, given once it has not failed
    try:
        if suffix in (".ply", ".ply.gz"):
            try:
                if suffix == ".ply":
                    mesh = _read_ply(path)
                else:                       # pbrt-v4's plymesh takes them
                    with gzip.open(path) as f:
                        mesh = _read_ply(f, path)
            except UserError as e:          # the PLY reader's lines name the file: here, the field too
                raise UserError(f"{where}: {e}") from None
        elif suffix == ".obj":
            from pathtrace.scene.obj import parse_obj
            mesh = MeshData(*parse_obj(path.read_bytes(), f"{where}: {path}", notes.append))
        else:
            if suffix == ".gltf":
                _check_gltf_buffers(path, f"{where}: {path}")
            mesh = _read_with_trimesh(path, suffix)
    except UserError:
        raise
    except Exception as e:     # the parsers raise anything on a malformed file; a library's own slip says nothing
        said = str(e) and not isinstance(e, (NameError, AttributeError, TypeError, AssertionError))   # (Unbound...)
        raise UserError(f"{where}: {path}: not a readable {suffix[1:].upper()} mesh "
                        f"({type(e).__name__ + ': ' + str(e).splitlines()[0] if said else 'malformed'})") from None
    for note in notes:
        warn(note)
    checked = check_mesh(*mesh, where=f"{where}: {path}", warn=warn, degenerate=degenerate)
    if kept_as is not None and len(checked.faces) == len(mesh.faces) and not notes:     # no warning
        mesh_cache.collect(kept_as, checked)
    return checked


class MeshFiles:
    """The mesh files a scene names, the large ones read ahead in threads in the order the
    reader names them: add() takes (path, where) pairs as read_mesh does, read() hands out one as
    read_mesh(path, where) would have read it then. Its problem or warning lines come out at
    read(), so that they keep the reader's order: the first bad file in file order is the one
    reported. A file read ahead under another `where` than read()'s (a reader's guess), with a
    problem or a warning, is read again for read()'s lines.

    Only files of LARGE bytes or more are read ahead in threads: NumPy releases the interpreter's
    lock in each operation on an array, and a small file's reading is hundreds of short ones,
    whose lock handovers between threads cost more than another core gives
    (docs/notes/performance-2026-11.md, 2026-11-28). MANY small OBJ files of PROCESS_BYTES or more
    in all are read in other processes (pathtrace.scene.mesh_processes): on PROCESS_CORES cores or
    more all of them, else half (_share). Not binary PLY files, which NumPy reads as views of their
    bytes, faster than the processes start (docs/notes/performance-2026-11.md, 2026-11-30)."""

    LARGE = 512 << 10
    MANY = 64
    PROCESS_BYTES = 32 << 20
    PROCESS_CORES = 4
    SHARE_BYTES = 24 << 20

    def __init__(self, requests=()):
        self.requests = []
        self.waiting = {}      # path -> the indices of its requests not yet read()
        self.futures = {}      # index of a request -> its Future
        self.submitted = 0
        self.taken = 0         # the requests before the latest read() one
        self.pool = None
        self.processes = None
        self.processed = {}    # path -> (where, Future) of its requests read in processes, not read() yet
        self.named_bytes = 0   # the sizes of the files of the requests
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
        self.workers = min(cores, 32)
        self.add(requests)

    def add(self, requests):
        small_obj, small_bytes = [], 0
        for path, where in requests:
            path = Path(path)
            try:
                info = path.stat()
            except (OSError, ValueError):      # read_mesh says what is wrong, when asked
                continue
            size = info.st_size
            self.named_bytes += size
            if self.named_bytes >= LARGE_SCENE_BYTES:
                large_scene_named.set()
            if size >= self.LARGE:
                self.waiting.setdefault(path, deque()).append(len(self.requests))
                self.requests.append((path, where))
            elif path.suffix.lower() == ".obj" and not mesh_cache.holds(stamp(path, info)):   # a kept one is read here
                small_obj.append((path, where, size))
                small_bytes += size
        if len(small_obj) >= self.MANY and small_bytes >= self.PROCESS_BYTES and self.processes is None:
            if self.workers >= self.PROCESS_CORES:
                self._read_in_processes([r[:2] for r in small_obj], self.workers)
            elif self.workers >= 2:
                self._share(small_obj)
        self._submit()

    def _share(self, requests):
        """On two or three cores, where two processes each reading all of them, each starting
        Python, lost to one: the later half of the small OBJ files (path, where, size) read in one
        other process while this one reads the first, where that half holds SHARE_BYTES or more
        (docs/notes/performance-2026-12.md, 2026-12-03: level at 32 MB in all, a loss where the
        other core is busy). A file named in both halves is read here: the process answers its
        whole share at once, which this one would wait for at the file's first read."""
        half = len(requests) // 2
        here = {path for path, _, _ in requests[:half]}
        there = [r for r in requests[half:] if r[0] not in here]
        if there and sum(size for _, _, size in there) >= self.SHARE_BYTES:
            self._read_in_processes([r[:2] for r in there], 1)

    def _read_in_processes(self, requests, processes: int):
        from pathtrace.scene.mesh_processes import Reading
        self.processes = Reading(requests, processes)
        for (path, where), future in zip(requests, self.processes.futures):
            self.processed.setdefault(path, deque()).append((where, future))

    def _submit(self):
        """Reads ahead up to two files a thread past the reader's latest, where there are two
        to read at least (one alone the reader waits for)."""
        end = min(self.taken + 2 * self.workers, len(self.requests))
        if self.submitted >= end or self.workers < 2 or len(self.requests) < 2:
            return
        if self.pool is None:
            self.pool = ThreadPoolExecutor(self.workers, thread_name_prefix="mesh-files")
        for i in range(self.submitted, end):
            self.futures[i] = self.pool.submit(_read_noting, *self.requests[i])
        self.submitted = end

    def read(self, path, where: str, degenerate=None) -> MeshData:
        """The mesh, as read_mesh(path, where, degenerate=degenerate) reads it. A file read
        ahead with a problem or a warning (a degenerate triangle among them) is read again
        where `degenerate` is given, which the threads do not take."""
        queued = self.processed.get(Path(path))
        if queued:
            read_as, future = queued.popleft()
        else:
            indices = self.waiting.get(Path(path))
            if not indices:
                return read_mesh(path, where, degenerate=degenerate)
            i = indices.popleft()
            self.taken = max(self.taken, i + 1)
            self._submit()
            future = self.futures.pop(i, None)
            if future is None:
                return read_mesh(path, where, degenerate=degenerate)
            read_as = self.requests[i][1]
        again = read_as != where or degenerate is not None
        try:
            mesh, notes = future.result()
        except UserError:
            if again:
                return read_mesh(path, where, degenerate=degenerate)
            raise
        if mesh is None or notes and again:     # None: its process failed (mesh_processes)
            return read_mesh(path, where, degenerate=degenerate)
        for note in notes:
            warn(note)
        return mesh

    def close(self):
        for future in self.futures.values():
            future.cancel()
        if self.pool is not None:
            self.pool.shutdown(wait=True)
        if self.processes is not None:
            self.processes.close()

    def __enter__(self):
        return self

    def __exit__(self, *_):
        self.close()


def _read_noting(path, where):
    """read_mesh(path, where) in a thread: the mesh and its warning lines, kept for the reader."""
    notes = []
    return read_mesh(path, where, notes.append), notes


_QUIET = threading.Lock()


@contextmanager
def _parsers_quiet():
    """The parsers' own warning lines silenced: they would precede pathtrace's one line (NumPy's
    loadtxt in plyfile on a cut PLY). warnings.catch_warnings sets the process's filters, and
    mesh files are read in threads (MeshFiles), so such parses run one at a time."""
    with _QUIET, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def check_mesh(vertices, faces, normals, uvs=None, where="", warn=warn, degenerate=None) -> MeshData:
    """Validates a mesh and drops its degenerate triangles (repeated corners or zero area), with
    a line to `warn`, or where `degenerate` is given, a call degenerate(dropped, total) in its
    stead, and a mesh left with no triangle is returned so (the caller decides; otherwise it is
    refused). Unusable normals or texture coordinates (the wrong count) are dropped; NaN or
    infinite texture coordinates are refused."""
    vertices = np.asarray(vertices, np.float64).reshape(-1, 3)
    faces = np.asarray(faces, np.int64).reshape(-1, 3)
    if len(faces) == 0:
        raise UserError(f"{where}: the mesh has no triangles")
    if len(faces) > MAX_TRIANGLES:
        raise UserError(f"{where}: {len(faces)} triangles is more than pathtrace takes ({MAX_TRIANGLES})")
    if not np.all(np.isfinite(vertices)):
        bad = int(np.argmax(~np.all(np.isfinite(vertices), axis=1)))
        raise UserError(f"{where}: vertex {bad} is not finite ({vertices[bad].tolist()})")
    if np.any(np.abs(vertices) > MAX_COORDINATE):
        raise UserError(f"{where}: vertex coordinates beyond {MAX_COORDINATE:g} cannot be traced in float32")
    if faces.min() < 0 or faces.max() >= len(vertices):
        bad = int(np.argmax((faces < 0).any(axis=1) | (faces >= len(vertices)).any(axis=1)))
        raise UserError(f"{where}: face {bad} refers to vertex {faces[bad].tolist()}, "
                        f"but the mesh has {len(vertices)} vertices")
    if normals is not None:
        normals = np.asarray(normals, np.float64).reshape(-1, 3)
        if len(normals) != len(vertices) or not np.all(np.isfinite(normals)):
            normals = None     # unusable normals: shade flat rather than refuse the mesh
    if uvs is not None:
        uvs = np.asarray(uvs, np.float64).reshape(-1, 2) if np.size(uvs) % 2 == 0 else np.zeros((0, 2))
        if len(uvs) != len(vertices):
            uvs = None
        elif not np.all(np.isfinite(uvs)) or np.any(np.abs(uvs) > MAX_COORDINATE):
            bad = int(np.argmax(~np.all(np.isfinite(uvs) & (np.abs(uvs) <= MAX_COORDINATE), axis=1)))
            raise UserError(f"{where}: the texture coordinates of vertex {bad} are not finite ({uvs[bad].tolist()})")
    # the float32 corners the kernels get, their edges' cross products in float64 (1e17 squared
    # overflows float32), by components: a triangle has area where any component is nonzero
    v = vertices.astype(np.float32).astype(np.float64)
    a = np.take(v, faces[:, 0], axis=0)      # np.take: 3-4x faster than v[faces[:, 0]]
    e1, e2 = np.take(v, faces[:, 1], axis=0) - a, np.take(v, faces[:, 2], axis=0) - a
    keep = ((e1[:, 1] * e2[:, 2] != e1[:, 2] * e2[:, 1]) | (e1[:, 2] * e2[:, 0] != e1[:, 0] * e2[:, 2])
            | (e1[:, 0] * e2[:, 1] != e1[:, 1] * e2[:, 0]))
    if not keep.all():
        if degenerate is not None:
            degenerate(int(np.count_nonzero(~keep)), len(faces))
            return MeshData(vertices, faces[keep], normals, uvs)
        warn(f"{where}: dropped {np.count_nonzero(~keep)} degenerate triangle(s) of {len(faces)}")
        faces = faces[keep]
        if len(faces) == 0:
            raise UserError(f"{where}: every triangle of the mesh is degenerate")
    return MeshData(vertices, faces, normals, uvs)


def orient_by_normals(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The faces, each wound so that its geometric normal lies on its vertex normals' side (the
    faces themselves where all agree already). pathtrace tells front from back by the geometric
    normal (kernels/shapes/triangle.cl); pbrt-v4 turns the geometric normal to the shading
    normal's side, and Mitsuba 3 decides the side by the shading frame (its one-sided BSDFs and
    area emitters test cos_theta(si.wi) there, src/render/mesh.cpp keeping the interpolated
    normal unturned): either way the side of the normals."""
    # rows gathered by np.take, faster than indexing with the faces (as app/compiler/compiled.py's)
    f0, f1, f2 = faces[:, 0], faces[:, 1], faces[:, 2]
    p0 = np.take(vertices, f0, axis=0)
    a, b = (np.take(vertices, f1, axis=0) - p0).T, (np.take(vertices, f2, axis=0) - p0).T
    n = (np.take(normals, f0, axis=0) + np.take(normals, f1, axis=0) + np.take(normals, f2, axis=0)).T
    # (a x b) . n, written out: np.cross costs more than the products on small meshes
    flip = (a[1] * b[2] - a[2] * b[1]) * n[0] + (a[2] * b[0] - a[0] * b[2]) * n[1] \
        + (a[0] * b[1] - a[1] * b[0]) * n[2] < 0
    if not flip.any():
        return faces
    faces = faces.copy()
    faces[flip] = faces[flip][:, ::-1]
    return faces


def place_mesh(vertices, faces, normals, m: np.ndarray, flip: bool, orient: bool, where: str) -> tuple:
    """(vertices, faces, normals, turned) of a mesh of the object's space moved into the world by
    m: its faces turned round where `flip` (Mitsuba's flip_normals, pbrt's ReverseOrientation; its
    normals too) and where m swaps handedness (the front kept where it was), and where `orient`,
    each wound to its normals' side (orient_by_normals; `turned`: whether any face was)."""
    if flip:
        faces = faces[:, ::-1]
        normals = None if normals is None else -normals
    vertices = transform_points(m, vertices)
    if np.any(np.abs(vertices) > MAX_COORDINATE):
        raise UserError(f"{where}: the transformed vertices lie beyond {MAX_COORDINATE:g}, which float32 cannot trace")
    if normals is not None:
        normals = transform_normals(m, normals)
    if flips_handedness(m):
        faces = faces[:, ::-1]
    oriented = orient_by_normals(vertices, faces, normals) if orient and normals is not None else faces
    return vertices, oriented, normals, oriented is not faces


# Mitsuba 3's cube texture coordinates per face (axis, sign): u and v each (s * p[k] + 1) / 2 for
# the point's coordinate k and a sign s, as (k_u, s_u, k_v, s_v); read off Mitsuba 3.9's cube
_CUBE_UV = {(2, 1): (1, 1, 0, 1), (2, -1): (1, -1, 0, 1), (0, 1): (1, 1, 2, -1),
            (0, -1): (1, 1, 2, 1), (1, 1): (0, -1, 2, -1), (1, -1): (2, 1, 0, 1)}


def mitsuba_cube():
    """Mitsuba 3's cube: [-1, 1]^3, faces counter-clockwise seen from outside, with its uvs."""
    vertices, faces, uvs = [], [], []
    for axis in range(3):
        for sign in (-1, 1):
            u, v = (axis + 1) % 3, (axis + 2) % 3
            base = len(vertices)
            ku, su, kv, sv = _CUBE_UV[axis, sign]
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = np.zeros(3)
                p[axis], p[u], p[v] = sign, a, b
                vertices.append(p)
                uvs.append(((su * p[ku] + 1) / 2, (sv * p[kv] + 1) / 2))
            # (u, v, axis) is right-handed, so these corners run counter-clockwise about +axis
            quad = [base, base + 1, base + 2, base + 3] if sign > 0 else [base, base + 3, base + 2, base + 1]
            faces += [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]]
    return np.array(vertices), np.array(faces), np.array(uvs)


def mitsuba_rectangle():
    """Mitsuba 3's rectangle: [-1, 1]^2 at z = 0 facing +z, uv (0, 0) at (-1, -1)."""
    vertices = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float64)
    return vertices, np.array([[0, 1, 2], [0, 2, 3]]), (vertices[:, :2] + 1) / 2


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Smooth normals at the vertices: each face's unit normal weighted by its angle at the
    vertex (Thuermer and Wuethrich 1998), as Mitsuba 3 computes them for a mesh that has none.
    A vertex of degenerate faces only gets a zero normal, which the kernels shade flat."""
    corners = vertices[faces]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    normals = np.zeros_like(vertices, dtype=np.float64)
    for i in range(3):
        d0 = corners[:, (i + 1) % 3] - corners[:, i]
        d1 = corners[:, (i + 2) % 3] - corners[:, i]
        d0 /= np.maximum(np.linalg.norm(d0, axis=1, keepdims=True), 1e-300)
        d1 /= np.maximum(np.linalg.norm(d1, axis=1, keepdims=True), 1e-300)
        angle = np.arccos(np.clip(np.sum(d0 * d1, axis=1), -1, 1))
        np.add.at(normals, faces[:, i], n * angle[:, None])
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)


# PLY's scalar types as NumPy's
PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
             "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
             "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


def is_closed(vertices: np.ndarray, faces: np.ndarray) -> bool:
    """Whether a mesh encloses a volume: every edge, its corners welded by position (a cube's
    faces may each have corners of their own), is shared by exactly two triangles."""
    _, weld = np.unique(vertices, axis=0, return_inverse=True)
    corners = weld.reshape(-1)[faces]
    edges = np.sort(np.concatenate([corners[:, [0, 1]], corners[:, [1, 2]], corners[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))


def _read_binary_triangles(data: bytes, path):
    """The vertex records and triangles of a binary PLY file whose elements are a vertex of
    scalar properties and a face of one index list, every face a triangle (what exporters and
    pbrt's scenes write), as NumPy views of the buffer; None for any other file (plyfile reads
    those, a Python loop over the faces: 200x slower)."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        return None
    lines = data[:end].decode("ascii", "replace").splitlines()
    body = data.find(b"\n", end) + 1
    fmt = next((line.split() for line in lines if line.startswith("format ")), None)
    if fmt is None or len(fmt) < 2 or fmt[1] not in ("binary_little_endian", "binary_big_endian"):
        return None
    order = "<" if fmt[1] == "binary_little_endian" else ">"
    elements = []
    for line in lines:
        words = line.split()
        if words[:1] == ["element"] and len(words) == 3 and words[2].isdigit():
            elements.append((words[1], int(words[2]), []))
        elif words[:1] == ["property"] and elements:
            elements[-1][2].append(words[1:])
    if [e[0] for e in elements] != ["vertex", "face"]:
        return None
    (_, n_vertices, vertex_props), (_, n_faces, face_props) = elements
    if any(len(p) != 2 or p[0] not in PLY_TYPES for p in vertex_props) or len(face_props) != 1:
        return None
    face = face_props[0]
    if len(face) != 4 or face[0] != "list" or face[1] not in PLY_TYPES or face[2] not in PLY_TYPES \
            or face[3] not in ("vertex_indices", "vertex_index"):
        return None
    vertex_type = np.dtype([(name, order + PLY_TYPES[t]) for t, name in vertex_props])
    face_type = np.dtype([("n", order + PLY_TYPES[face[1]]), ("i", order + PLY_TYPES[face[2]], 3)])
    need = vertex_type.itemsize * n_vertices + face_type.itemsize * n_faces
    if body + need > len(data):
        raise UserError(f"{path}: the PLY file holds {len(data) - body} bytes of data where its header "
                        f"claims {n_vertices} vertices and {n_faces} faces (at least {need} bytes)")
    faces = np.frombuffer(data, face_type, n_faces, body + vertex_type.itemsize * n_vertices)
    if not np.all(faces["n"] == 3):
        return None
    return np.frombuffer(data, vertex_type, n_vertices, body), faces["i"].astype(np.int64)


def _read_ply(source, path=None):
    """A PLY mesh from a path, or from a file object `source` read from `path`."""
    path = path or source
    data = source.read(MAX_FILE_BYTES + 1) if path is not source else Path(path).read_bytes()
    if len(data) > MAX_FILE_BYTES:
        raise UserError(f"{path}: the PLY file decompresses to more than {MAX_FILE_BYTES >> 30} GB")
    fast = _read_binary_triangles(data, path)
    if fast is not None:
        return _ply_mesh(*fast, path)
    from plyfile import PlyData
    with _parsers_quiet():
        ply = PlyData.read(io.BytesIO(data))
        names = [e.name for e in ply.elements]
        if "vertex" not in names or "face" not in names:
            raise UserError(f"{path}: the PLY file has no {'vertex' if 'vertex' not in names else 'face'} element")
        return _ply_mesh(ply["vertex"].data, ply["face"].data, path)


def _ply_mesh(v, faces, path) -> MeshData:
    """A mesh of a PLY file's vertex records and its triangles, or its face records (polygons)."""
    fields = v.dtype.names
    for k in ("x", "y", "z", "nx", "ny", "nz"):
        if k in fields and v.dtype[k].kind not in "fiu":
            raise UserError(f"{path}: the PLY vertex property '{k}' must be a number, not a list")
        if k in "xyz" and k not in fields:
            raise UserError(f"{path}: the PLY vertices have no '{k}'")
    vertices = np.column_stack([v["x"], v["y"], v["z"]])
    normals = np.column_stack([v["nx"], v["ny"], v["nz"]]) if {"nx", "ny", "nz"} <= set(fields) else None
    names = next((pair for pair in PLY_UV_NAMES if set(pair) <= set(fields)), None)
    if names and any(v.dtype[k].kind not in "fiu" for k in names):
        raise UserError(f"{path}: the PLY vertex property '{names[0]}' must be a number, not a list")
    uvs = np.column_stack([v[names[0]], v[names[1]]]) if names else None
    if faces.dtype.names is None:
        return MeshData(vertices, faces, normals, uvs)
    key = next((k for k in ("vertex_indices", "vertex_index") if k in faces.dtype.names), None)
    if key is None:
        raise UserError(f"{path}: the PLY faces have no vertex_indices")
    return MeshData(vertices, triangulate(faces[key]), normals, uvs)


def triangulate(polygons) -> np.ndarray:
    """Polygons (a sequence of index arrays) as triangle fans."""
    polygons = list(polygons)
    lengths = np.fromiter((len(p) for p in polygons), np.int64, len(polygons))
    out = []
    for n in np.unique(lengths):
        if n < 3:
            continue
        group = np.stack([polygons[i] for i in np.flatnonzero(lengths == n)])
        if group.dtype.kind == "f" and not np.all(np.isfinite(group) & (group == np.round(group))):
            raise ValueError("face vertex indices must be whole numbers")   # a PLY list of floats
        group = group.astype(np.int64)
        for k in range(1, n - 1):
            out.append(group[:, [0, k, k + 1]])
    return np.concatenate(out) if out else np.zeros((0, 3), np.int64)


def _trimesh_uvs(visual):
    """trimesh's texture coordinates (v = 0 at the bottom) in Mitsuba's convention, or None."""
    uv = getattr(visual, "uv", None)
    if uv is None or len(uv) == 0:
        return None
    uv = np.array(uv, np.float64).reshape(-1, 2)
    uv[:, 1] = 1.0 - uv[:, 1]
    return uv


def _check_gltf_buffers(path: Path, where: str):
    """The files a glTF's buffers and images name are regular files of bounded size, checked
    before trimesh opens them (a buffer that is a FIFO hung the load)."""
    import json
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as e:
        raise UserError(f"{where}: not a readable glTF file ({type(e).__name__})") from None
    if not isinstance(data, dict):
        raise UserError(f"{where}: not a glTF file (its JSON is not an object)")
    for kind in ("buffers", "images"):
        entries = data.get(kind, [])
        for k, entry in enumerate(entries if isinstance(entries, list) else []):
            uri = entry.get("uri") if isinstance(entry, dict) else None
            if isinstance(uri, str) and not uri.startswith("data:"):
                from urllib.parse import unquote
                check_regular_file(Path(path).parent / unquote(uri), f"{where}: {kind}[{k}]", "file", MAX_FILE_BYTES)


def _read_with_trimesh(path, suffix):
    import trimesh

    from pathtrace.scene.transform import transform_normals, transform_points

    with _parsers_quiet():
        scene = trimesh.load(str(path), file_type=suffix[1:], force="scene", process=False)
        parts = []
        for node in scene.graph.nodes_geometry:
            matrix, name = scene.graph[node]
            geometry = scene.geometry[name]
            if not hasattr(geometry, "faces"):
                continue
            has_normals = suffix != ".stl" and "vertex_normals" in geometry._cache
            normals = transform_normals(matrix, geometry.vertex_normals) if has_normals else None
            parts.append((transform_points(matrix, geometry.vertices), geometry.faces, normals,
                          _trimesh_uvs(getattr(geometry, "visual", None))))
        return _concatenate(parts)


def _triangles(faces) -> np.ndarray:
    """Faces as triangles: polygons (quads from an OBJ file) become fans."""
    faces = np.asarray(faces, np.int64)
    return faces.reshape(-1, 3) if faces.ndim == 2 and faces.shape[1] == 3 else triangulate(list(faces))


def _concatenate(parts):
    """Parts (vertices, faces, normals, uvs) as one mesh; normals and uvs where every part has
    them."""
    parts = [p for p in parts if p[0] is not None and p[1] is not None and len(p[1])]
    if not parts:
        return MeshData(np.zeros((0, 3)), np.zeros((0, 3), np.int64), None)
    offsets = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
    vertices = np.concatenate([np.asarray(p[0], np.float64).reshape(-1, 3) for p in parts])
    faces = np.concatenate([_triangles(p[1]) + o for p, o in zip(parts, offsets)])

    def joined(k, width):
        if all(p[k] is not None and len(p[k]) == len(p[0]) for p in parts):
            return np.concatenate([np.asarray(p[k], np.float64).reshape(-1, width) for p in parts])
        return None
    return MeshData(vertices, faces, joined(2, 3), joined(3, 2))


def write_ply(path: Path, vertices, faces, normals=None, uvs=None):
    """A binary PLY file of a triangle mesh, with its normals and uvs where it has them (as
    _read_binary_triangles reads it back)."""
    columns = [("x", vertices[:, 0]), ("y", vertices[:, 1]), ("z", vertices[:, 2])]
    if normals is not None:
        columns += [("nx", normals[:, 0]), ("ny", normals[:, 1]), ("nz", normals[:, 2])]
    if uvs is not None:
        columns += [("u", uvs[:, 0]), ("v", uvs[:, 1])]
    records = np.zeros(len(vertices), [(name, "<f4") for name, _ in columns])
    for name, values in columns:
        records[name] = values
    triangles = np.zeros(len(faces), [("n", "u1"), ("i", "<i4", 3)])
    triangles["n"], triangles["i"] = 3, faces
    header = "ply\nformat binary_little_endian 1.0\n" + f"element vertex {len(vertices)}\n" \
        + "".join(f"property float {name}\n" for name, _ in columns) \
        + f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    Path(path).write_bytes(header.encode() + records.tobytes() + triangles.tobytes())

