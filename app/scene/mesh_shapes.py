"""The scene formats' mesh shapes: pathtrace's and Mitsuba 3's mesh files (`obj`, `ply`) and
pbrt-v4's `plymesh`, Mitsuba 3's `rectangle` and `cube`, pbrt-v4's `trianglemesh`,
`bilinearmesh` and `loopsubdiv`. Each declares its names in the formats and its parameters
(app/parameters.py), by which the readers read it, and makes its triangles in its object's
space from their values; the readers place them (meshes.place_mesh) by the format's transform
and orientation, and pbrt's reader turns their texture v round as it turns every mesh's."""

from dataclasses import dataclass
from typing import Callable

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.scene.loop_subdivision import LEVELS, loop_subdivide
from pathtrace.scene.meshes import check_mesh, mitsuba_cube, mitsuba_rectangle, vertex_normals
from pathtrace.scene.serialized import read_serialized

FLIP = Parameter("flip_normals", "bool", False, doc="its front turned round", mitsuba="flip_normals")


@dataclass
class MeshSource:
    """What a mesh shape needs of the reader of its element: read(name) -> (MeshData, path), the
    mesh file `name` relative to the scene file, read ahead (meshes.MeshFiles); check(vertices,
    faces, normals, uvs) -> MeshData, meshes.check_mesh naming the element; warn(text), a warning
    naming it; locate(name) -> (path, where), the file `name` relative to the scene file and what
    names the element, for a shape that reads its file itself."""
    read: Callable = None
    check: Callable = None
    warn: Callable = None
    locate: Callable = None


class MeshShape:
    name = ""
    formats: dict = {}        # its names in Mitsuba 3 and pbrt-v4 ({format: name or names})
    parameters: tuple = ()
    unsupported: dict = {}    # {format: {name: why}}: what a format's shape gives and pathtrace has
                              # not, warned of where a file gives it (why None: read, not warned of)

    def triangles(self, values: dict, source: MeshSource) -> tuple:
        """(MeshData in its object's space, the path of its mesh file or "", whether its normals
        were computed where the file has none) from the values of its parameters by
        pathtrace's names. Raises ValueError ("<name>: <problem>", or a problem of the whole)."""
        raise NotImplementedError


class FileMesh(MeshShape):
    """A mesh file (app/scene/meshes.py: read_mesh), its normals dropped where `face_normals`,
    and where it has none, made from its faces where `smooth` (Mitsuba 3 smooths such a file)."""
    name = "file"
    formats = {"mitsuba": ("obj", "ply"), "pbrt": "plymesh"}
    parameters = (Parameter("file", "string", doc="the mesh file, relative to the scene file", mitsuba="filename",
                            pbrt="filename"),
                  Parameter("face_normals", "bool", False, doc="the file's normals dropped: flat shading",
                            mitsuba="face_normals"),
                  Parameter("smooth", "bool", False, doc="angle-weighted vertex normals where the file has none",
                            mitsuba_default=True),
                  FLIP)
    unsupported = {"pbrt": dict.fromkeys(("displacement", "edgelength"), "pathtrace does not displace meshes")}

    def triangles(self, values, source):
        name = values.get("file")
        if not name:
            raise ValueError("needs a filename" if name is None else "file: must be a file name, got ''")
        (vertices, faces, normals, uvs), path = self.read(name, values, source)
        if values.get("face_normals"):
            normals = None
        smoothed = normals is None and values.get("smooth", False) and not values.get("face_normals")
        if smoothed:
            normals = vertex_normals(vertices, faces)
        return (vertices, faces, normals, uvs), path, smoothed

    @staticmethod
    def read(name, values, source) -> tuple:
        """(MeshData, its file's path) of the file `name`."""
        return source.read(name)


class Serialized(FileMesh):
    """Mitsuba's serialized mesh: mesh `shape_index` of the file (app/scene/serialized.py), as a
    mesh file otherwise. No file path is given back: `convert` writes the mesh anew, as no other
    format reads the file."""
    name = "serialized"
    formats = {"mitsuba": "serialized"}
    parameters = (*FileMesh.parameters[:1],
                  Parameter("shape_index", "integer", 0, low=0, high=2**32 - 1,
                            doc="which of the file's meshes (from 0)", mitsuba="shape_index"),
                  *FileMesh.parameters[1:])

    @staticmethod
    def read(name, values, source):
        path, where = source.locate(name)
        return check_mesh(*read_serialized(path, values.get("shape_index", 0), where), where=f"{where}: {path}"), ""


class Rectangle(MeshShape):
    """Mitsuba 3's rectangle (meshes.mitsuba_rectangle)."""
    name = "rectangle"
    formats = {"mitsuba": "rectangle"}
    parameters = (FLIP,)
    geometry = staticmethod(mitsuba_rectangle)

    def triangles(self, values, source):
        vertices, faces, uvs = self.geometry()
        return source.check(vertices, faces, None, uvs), "", False


class Cube(Rectangle):
    """Mitsuba 3's cube (meshes.mitsuba_cube)."""
    name = "cube"
    formats = {"mitsuba": "cube"}
    geometry = staticmethod(mitsuba_cube)


class TriangleMesh(MeshShape):
    """pbrt-v4's mesh of polygons of `corners` vertices written out: "point3 P", "integer
    indices" (which may be left out where P is one polygon), and normals "N" and texture
    coordinates "uv" per vertex (pbrt-v4: GetPoint2fArray("uv"); pbrt-v3 wrote floats)."""
    name = "trianglemesh"
    formats = {"pbrt": "trianglemesh"}
    corners = 3
    parameters = (Parameter("vertices", "points", doc="the vertices", pbrt="P"),
                  Parameter("indices", "integers", doc="the polygons' vertex indices", pbrt="indices", optional=True),
                  Parameter("normals", "normals", doc="a normal per vertex", pbrt="N", optional=True),
                  Parameter("uvs", "pairs", doc="texture coordinates per vertex", pbrt="uv", optional=True))
    unsupported = {"pbrt": {"S": None, "faceIndices": None}}     # tangents and ptex faces: unused

    def triangles(self, values, source):
        vertices, polygons = self.polygons(values)
        normals, uvs = values.get("normals"), values.get("uvs")
        if normals is not None and len(normals) != 3 * len(vertices):
            raise ValueError(f"normals: has {len(normals) // 3} normals for {len(vertices)} vertices")
        if uvs is not None and len(uvs) != 2 * len(vertices):
            raise ValueError(f"uvs: has {len(uvs) // 2} uvs for {len(vertices)} vertices")
        return source.check(vertices, self.split(polygons), None if normals is None else normals.reshape(-1, 3),
                            None if uvs is None else uvs.reshape(-1, 2)), "", False

    def polygons(self, values) -> tuple:
        """vertices (V, 3) and polygons (N, corners)."""
        if "vertices" not in values:
            raise ValueError(f'a {self.name} needs "point3 P"')
        vertices = values["vertices"].reshape(-1, 3)
        indices = values.get("indices")
        if indices is None:
            if len(vertices) != self.corners:
                raise ValueError(f'a {self.name} needs "integer indices" unless it has {self.corners} vertices')
            indices = np.arange(self.corners)
        if len(indices) % self.corners:
            raise ValueError(f"indices: takes polygons of {self.corners} indices each; got {len(indices)}")
        return vertices, indices.reshape(-1, self.corners)

    @staticmethod
    def split(polygons):
        """Triangles of the polygons."""
        return polygons


class BilinearMesh(TriangleMesh):
    """pbrt-v4's bilinear patches, corners p00 p10 p01 p11, each two triangles of the patch's
    orientation (exact where the patch is planar)."""
    name = "bilinearmesh"
    formats = {"pbrt": "bilinearmesh"}
    corners = 4
    unsupported = {"pbrt": {"faceIndices": None}}     # pbrt-v4's BilinearPatch::CreateMesh reads no "S"

    @staticmethod
    def split(polygons):
        return np.concatenate([polygons[:, [0, 1, 3]], polygons[:, [0, 3, 2]]])


class LoopSubdivision(TriangleMesh):
    """pbrt-v4's Loop subdivision surface: its control mesh subdivided `levels` times and pushed to
    the limit surface, with the limit's normals, as pbrt-v4 makes it (app/scene/loop_subdivision.py)."""
    name = "loopsubdiv"
    formats = {"pbrt": "loopsubdiv"}
    parameters = TriangleMesh.parameters[:2] + (
        Parameter("levels", "integer", LEVELS, low=0, high=12, doc="how many times each triangle is split in four",
                  pbrt="levels"),)
    unsupported = {}         # pbrt-v4's loopsubdiv reads no tangents or ptex faces

    def triangles(self, values, source):
        vertices, polygons = self.polygons(values)
        if not np.all(np.isfinite(vertices)):
            raise ValueError("vertices: not all finite")
        # every control triangle, a degenerate one too, as pbrt-v4 subdivides them
        vertices, faces, normals = loop_subdivide(vertices, polygons, values.get("levels", LEVELS))
        return source.check(vertices, faces, normals, None), "", False


MESH_SHAPES = {k.name: k() for k in (FileMesh, Serialized, Rectangle, Cube, TriangleMesh, BilinearMesh,
                                     LoopSubdivision)}
