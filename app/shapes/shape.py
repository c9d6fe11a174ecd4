"""Analytic shapes: what every kind provides on the host, and a shape of a scene. A kind
(app/shapes/<kind>.py, registered in app/shapes/registry.py) gives its parameters' checks,
its object-space bounds, area and normals, for the BVH, the light table and the light tree;
its kernel file (kernels/shapes/<kind>.cl) intersects, parameterises and samples it. The
kernels keep a shape as a primitive of the triangle range that names its kind
(kernels/shapes/analytic.cl), so the BVH, its builders and the light tree see only its bounds."""

import math
from dataclasses import dataclass

import numpy as np

from pathtrace.shapes.texture_uv import TextureUV

ROWS = 8
"""float4 rows of the side table per shape (kernels/shapes/analytic.cl)."""

MIN_DETERMINANT = 1e-12
"""The least magnitude of the determinant of a shape's to_world's 3x3 part: nearer singular, the
inverse that the kernels intersect with (kernels/shapes/analytic.cl) is beyond float32's precision."""


TURN_Z = np.diag([1.0, 1.0, -1.0, 1.0])
"""The mirror of z. Mitsuba's sphere v = theta / pi is pbrt-v4's v of the sphere with z turned
round (theta -> pi - theta)."""


def turned_z(params) -> tuple:
    """(params, object transform) of pbrt-v4's shape of parameters (radius, z_min, z_max,
    phi_max), a sphere or a cylinder, with z turned round (TURN_Z, the z range mirrored): the same
    surface, its normal the same, its texture v = 1 - pbrt's v, as the pbrt reader turns every
    mesh's v (pbrt-v4's ImageTexture looks images up at (u, 1 - v); pathtrace's images have
    v = 0 at the top)."""
    radius, z_min, z_max, phi_max = params
    return (radius, -z_max, -z_min, phi_max), TURN_Z.copy()


def flattened(to_world) -> bool:
    """Whether a shape under the 4x4 transform `to_world` is too near flat to be traced."""
    return not abs(np.linalg.det(np.asarray(to_world, np.float64)[:3, :3])) >= MIN_DETERMINANT


class ShapeKind:
    """One kind of analytic shape, the four numbers of whose parameters (row 6 of its rows)
    its kernel file documents, declared in `parameters` in that order (app/parameters.py: their
    TOML and pbrt-v4 names, defaults and documentation, from which the readers read them and
    docs/scene-format.md's tables are generated)."""
    name = ""
    formats: dict = {}            # its names in Mitsuba 3 and pbrt-v4 ({format: name})
    doc = ""
    parameters: tuple = ()
    angles: tuple = ()            # the parameters files give in degrees (the kernels take radians)
    mitsuba_parameters: tuple = ()   # Mitsuba 3's (no TOML name; mitsuba_default), which from_mitsuba
                                     # maps onto the shape
    unsupported: dict = {}        # {format: {name: why}}: what a format's shape has and pathtrace's has
                                  # not (as a light's), none yet
    examples: tuple = ()          # parameter sets (the kernels') the registry's tests put it through

    def params_from(self, values: dict) -> tuple:
        """The kernels' four numbers from the declared parameters' values by name (as files give
        them: degrees for `angles`; absent ones take their defaults)."""
        out = []
        for p in self.parameters:
            v = values.get(p.name, p.default)
            v = None if v is None else float(v)      # None: optional, its default the kind's (normalised)
            out.append(math.radians(v) if v is not None and p.name in self.angles else v)
        return self.normalised(tuple(out))

    def file_values(self, params) -> dict:
        """params_from's inverse, by name: what a file states."""
        return {p.name: math.degrees(v) if p.name in self.angles else float(v) for p, v in zip(self.parameters, params)}

    def normalised(self, params) -> tuple:
        """params as the kernels take them, from a file's values (pbrt-v4 clamps and orders some)."""
        return params

    def from_mitsuba(self, values: dict, to_world: np.ndarray, where: str) -> tuple:
        """(params, object transform, TextureUV, flip) of Mitsuba 3's shape of this kind, from the
        values of its mitsuba_parameters (given or their mitsuba_default), by their Mitsuba names;
        the object transform goes before to_world; `where` (file:line) for its warnings."""
        raise NotImplementedError

    def from_pbrt(self, params) -> tuple:
        """(params, object transform, TextureUV) of pbrt-v4's shape of parameters `params`, the
        object transform going before the CTM (identity: the kind's own), its texture coordinates
        those at which pathtrace's lookup reads the texel pbrt-v4's reads at (u, 1 - v)."""
        raise NotImplementedError

    def check(self, params) -> str | None:
        """What is wrong with parameters `params`, or None."""
        raise NotImplementedError

    def object_bounds(self, params) -> tuple:
        """(lower, upper) corners of the box round the shape in its object's space."""
        raise NotImplementedError

    def area(self, params) -> float:
        """The area in its object's space."""
        raise NotImplementedError

    def object_normals(self, params, n: int) -> np.ndarray:
        """(n, 3) unit normals at n points spread evenly over the area (for the world area under
        a transform that stretches unevenly)."""
        raise NotImplementedError

    def normal_cone(self, params) -> tuple:
        """(axis, cos of its spread) of the cone holding every normal, in its object's space."""
        raise NotImplementedError

    def too_flat(self, shape) -> bool:
        """Whether `shape` is under a transform too near singular for the inverse the kernels
        intersect it through (flattened) and stays this kind: a whole sphere that the sphere range
        can render (fast_range, its material reading no frame) needs no inverse."""
        return flattened(shape.to_world) and self.fast_range(shape, False) is None

    @staticmethod
    def fast_range(shape, reads_frame: bool) -> tuple | None:
        """(centre, radius) of a sphere of the sphere range that renders `shape` alike, or None
        (SceneBuilder.add_shape keeps such a shape there); `reads_frame`: whether its material
        reads texture coordinates or tangents (MaterialTable.reads_frame)."""
        return None


class Quadric(ShapeKind):
    """A pbrt-v4 quadric about the z axis (disk, cylinder), its first parameter the radius and
    its last phi_max (radians): its checks and its box from what each such kind adds."""

    def own_problem(self, params) -> str | None:
        """What is wrong with its parameters besides the radius and phi_max, or None."""
        return None

    def z_range(self, params) -> tuple:
        """(lowest, highest) z of its points in its object's space."""
        raise NotImplementedError

    def check(self, params):
        radius, phi_max = params[0], params[-1]
        if not radius > 0:
            return f"radius must be positive, got {radius:g}"
        return self.own_problem(params) or (
            None if 0 < phi_max <= 2 * math.pi else f"phi_max must be in (0, 360] degrees, got {math.degrees(phi_max):g}")

    def object_bounds(self, params):
        radius = params[0]
        z_min, z_max = self.z_range(params)
        return np.array([-radius, -radius, z_min]), np.array([radius, radius, z_max])


@dataclass
class Shape:
    """An analytic shape of a scene: a kind's shape in its object's space, placed by `to_world`."""
    name: str
    kind: str                     # a name of pathtrace.shapes.SHAPES
    params: tuple                 # its four parameters (kernels/shapes/<kind>.cl)
    to_world: np.ndarray          # (4, 4) world from object
    material: int                 # row of the scene's MaterialTable
    flip: bool = False            # its front is the opposite of the kind's normal
    texture_uv: TextureUV = TextureUV.KIND   # its texture coordinates of the kind's (u, v)
    media: object = None          # the MediumInterface it bounds, or None

    # as the compiled scene's per-mesh tables read it: one primitive, no corner normals or uvs
    faces = np.zeros((1, 3), np.int32)
    normals = None
    uvs = None

    def __repr__(self) -> str:
        return f"<Shape {self.name!r}: {self.kind} {tuple(float(p) for p in self.params)}, material {self.material}>"

    @property
    def det(self) -> float:
        return float(np.linalg.det(np.asarray(self.to_world, np.float64)[:3, :3]))

    def rows(self) -> np.ndarray:
        """Its ROWS float4 rows of the side table."""
        m = np.asarray(self.to_world, np.float64)
        out = np.zeros((ROWS, 4), np.float32)
        out[0:3] = m[:3]
        out[3:6] = np.linalg.inv(m)[:3]
        out[6] = self.params
        out[7, :3] = (-1.0 if self.flip else 1.0, self.texture_uv.index, abs(self.det))
        return out

    def bounds(self, kind: ShapeKind) -> tuple:
        """(lower, upper) of its box in the world: its object box's corners moved."""
        lo, hi = kind.object_bounds(self.params)
        corners = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        world = corners @ np.asarray(self.to_world, np.float64)[:3].T
        return world.min(0), world.max(0)

    def world_normals(self, normals: np.ndarray) -> np.ndarray:
        """Object normals moved to the world (by the inverse transpose), on the front, unscaled."""
        inverse = np.linalg.inv(np.asarray(self.to_world, np.float64))[:3, :3]
        return (-1.0 if self.flip else 1.0) * normals @ inverse

    def world_area(self, kind: ShapeKind, samples: int = 64) -> float:
        """Its area in the world: the object area times the mean stretch |det M| |M^-T n| (the
        mean over an even spread of points, exact where the stretch is the same everywhere)."""
        stretch = abs(self.det) * np.linalg.norm(self.world_normals(kind.object_normals(self.params, samples)), axis=1)
        return kind.area(self.params) * float(stretch.mean())

    def world_normal_cone(self, kind: ShapeKind) -> tuple:
        """(unit axis, cos spread) of its front normals in the world. A full sphere of normals
        stays one; a single normal stays single."""
        axis, cos = kind.normal_cone(self.params)
        w = self.world_normals(np.array([axis], np.float64))[0]
        return w / np.linalg.norm(w), cos
