"""Reading triangle meshes: PLY through plyfile, OBJ, STL, glTF and GLB through trimesh. Every
problem is one line naming the file; degenerate triangles are dropped with a warning."""

from pathlib import Path

import numpy as np

from pathtrace.errors import UserError, short, warn
from pathtrace.files import check_regular_file

FORMATS = (".ply", ".obj", ".stl", ".gltf", ".glb")
MAX_FILE_BYTES = 4 << 30            # a mesh file larger than this is refused before reading
MAX_TRIANGLES = 64_000_000          # ~6 GB of device memory (docs/performance.md)
# the largest coordinate a shape may reach: the BVH's float32 surface areas, (2 x)^2, stay finite
MAX_COORDINATE = 1e18


def read_mesh(path: Path, where: str):
    """(vertices (V, 3) float64, faces (F, 3) int64, normals (V, 3) or None) of a mesh file.
    `where` names the field that refers to the file, for messages."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise UserError(f"{where}: {path}: unknown mesh format '{path.suffix}' "
                        f"(use {', '.join(FORMATS)})")
    check_regular_file(path, where, "mesh file", MAX_FILE_BYTES)
    try:
        if suffix == ".ply":
            vertices, faces, normals = _read_ply(path)
        elif suffix == ".obj":
            vertices, faces, normals = _read_obj(path, f"{where}: {path}")
        else:
            if suffix == ".gltf":
                _check_gltf_buffers(path, f"{where}: {path}")
            vertices, faces, normals = _read_with_trimesh(path, suffix)
    except UserError:
        raise
    except Exception as e:     # the parsers raise anything on a malformed file
        raise UserError(f"{where}: {path}: not a readable {suffix[1:].upper()} mesh "
                        f"({type(e).__name__}: {str(e).splitlines()[0] if str(e) else 'malformed'})") from None
    return check_mesh(vertices, faces, normals, f"{where}: {path}")


def check_mesh(vertices, faces, normals, where):
    """Validates a mesh and drops its degenerate triangles (repeated corners or zero area)."""
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
    # the float32 corners the kernels get, their cross products in float64 (1e17 squared
    # overflows float32)
    corners = vertices.astype(np.float32)[faces].astype(np.float64)
    area2 = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    keep = area2 > 0
    if not keep.all():
        warn(f"{where}: dropped {np.count_nonzero(~keep)} degenerate triangle(s) of {len(faces)}")
        faces = faces[keep]
        if len(faces) == 0:
            raise UserError(f"{where}: every triangle of the mesh is degenerate")
    return vertices, faces, normals


def _read_ply(path):
    from plyfile import PlyData

    ply = PlyData.read(str(path))
    names = [e.name for e in ply.elements]
    if "vertex" not in names or "face" not in names:
        raise UserError(f"{path}: the PLY file has no {'vertex' if 'vertex' not in names else 'face'} element")
    v = ply["vertex"].data
    fields = v.dtype.names
    for k in ("x", "y", "z", "nx", "ny", "nz"):
        if k in fields and v.dtype[k].kind not in "fiu":
            raise UserError(f"{path}: the PLY vertex property '{k}' must be a number, not a list")
        if k in "xyz" and k not in fields:
            raise UserError(f"{path}: the PLY vertices have no '{k}'")
    vertices = np.column_stack([v["x"], v["y"], v["z"]])
    normals = np.column_stack([v["nx"], v["ny"], v["nz"]]) if {"nx", "ny", "nz"} <= set(fields) else None
    face = ply["face"].data
    key = next((k for k in ("vertex_indices", "vertex_index") if k in face.dtype.names), None)
    if key is None:
        raise UserError(f"{path}: the PLY faces have no vertex_indices")
    return vertices, triangulate(face[key]), normals


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


def _read_obj(path, where):
    import io

    import trimesh.exchange.obj as obj

    with open(path, "r", encoding="utf-8", errors="replace") as f:
        text = f.read()
    _check_obj_faces(text, where)
    loaded = obj.load_obj(io.StringIO(text), skip_materials=True)
    parts = list(loaded.get("geometry", {}).values()) if "geometry" in loaded else [loaded]
    return _concatenate([(p.get("vertices"), p.get("faces"), p.get("vertex_normals")) for p in parts])


def _check_obj_faces(text: str, where: str):
    """Every face corner of an OBJ file names a vertex it has: an index from 1 to the number of
    `v` lines, or a negative one counting back from the last vertex read (the OBJ format's
    rule). trimesh otherwise fails with an IndexError that says nothing of the file."""
    vertices = 0
    for number, line in enumerate(text.splitlines(), 1):
        if line.startswith("v ") or line.startswith("v\t"):
            vertices += 1
        elif line.startswith("f ") or line.startswith("f\t"):
            for corner in line.split()[1:]:
                index = corner.split("/")[0]
                try:
                    k = int(index)
                except ValueError:
                    raise UserError(f"{where}: line {number}: face corner {short(corner)} is not a vertex index") from None
                if not (1 <= k <= vertices or -vertices <= k <= -1):
                    raise UserError(f"{where}: line {number}: face corner {k} names a vertex the file does not have "
                                    f"({vertices} so far; OBJ counts from 1)")


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

    scene = trimesh.load(str(path), file_type=suffix[1:], force="scene", process=False)
    parts = []
    for node in scene.graph.nodes_geometry:
        matrix, name = scene.graph[node]
        geometry = scene.geometry[name]
        if not hasattr(geometry, "faces"):
            continue
        has_normals = suffix != ".stl" and "vertex_normals" in geometry._cache
        normals = transform_normals(matrix, geometry.vertex_normals) if has_normals else None
        parts.append((transform_points(matrix, geometry.vertices), geometry.faces, normals))
    return _concatenate(parts)


def _triangles(faces) -> np.ndarray:
    """Faces as triangles: polygons (quads from an OBJ file) become fans."""
    faces = np.asarray(faces, np.int64)
    return faces.reshape(-1, 3) if faces.ndim == 2 and faces.shape[1] == 3 else triangulate(list(faces))


def _concatenate(parts):
    parts = [p for p in parts if p[0] is not None and p[1] is not None and len(p[1])]
    if not parts:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), None
    offsets = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
    vertices = np.concatenate([np.asarray(p[0], np.float64).reshape(-1, 3) for p in parts])
    faces = np.concatenate([_triangles(p[1]) + o for p, o in zip(parts, offsets)])
    with_normals = all(p[2] is not None and len(p[2]) == len(p[0]) for p in parts)
    normals = np.concatenate([np.asarray(p[2]).reshape(-1, 3) for p in parts]) if with_normals else None
    return vertices, faces, normals
