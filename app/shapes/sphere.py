"""The sphere (kernels/shapes/sphere.cl): pbrt-v4's `sphere` (radius, zmin, zmax, phimax) in its
object's space, an ellipsoid under a transform that stretches unevenly, and Mitsuba 3's `sphere`
(center, radius, flip_normals), which Mitsuba keeps round. A whole sphere under a similarity
whose texture coordinates are the sphere range's is kept in that range (fast_range)."""

import math

import numpy as np

from pathtrace.errors import warn
from pathtrace.parameters import Parameter
from pathtrace.shapes.shape import TURN_Z, ShapeKind, turned_z
from pathtrace.shapes.texture_uv import TextureUV

GOLDEN_ANGLE = math.pi * (3 - math.sqrt(5))


class Sphere(ShapeKind):
    name = "sphere"
    formats = {"mitsuba": "sphere", "pbrt": "sphere"}
    doc = ("The sphere about the origin, z_min to z_max, angles 0 to phi_max, facing outwards; uv "
           "(phi / phi_max, (theta - theta(z_min)) / (theta(z_max) - theta(z_min))), pbrt-v4's; "
           "under a non-uniform scale an ellipsoid. Mitsuba's stays round, of radius |to_world (1, 0, 0)|.")
    parameters = (Parameter("radius", "number", 1.0, doc="radius", pbrt="radius"),
                  Parameter("z_min", "number", doc="lower cut on the z axis (default -radius; clamped to "
                            "[-radius, radius])", pbrt="zmin", optional=True),
                  Parameter("z_max", "number", doc="upper cut on the z axis (default radius; clamped likewise)",
                            pbrt="zmax", optional=True),
                  Parameter("phi_max", "number", 360.0, pbrt="phimax",
                            doc="the angle it spans, degrees (more is 360: pbrt-v4 clamps it)"))
    angles = ("phi_max",)
    mitsuba_parameters = (Parameter(None, "point", doc="centre", mitsuba="center", mitsuba_default=(0.0, 0.0, 0.0)),
                          Parameter(None, "number", doc="radius", mitsuba="radius", mitsuba_default=1.0),
                          Parameter(None, "bool", doc="its front turned round", mitsuba="flip_normals",
                                    mitsuba_default=False))
    examples = ((1.0, -1.0, 1.0, 2 * math.pi), (1.2, -0.5, 0.9, math.radians(250)))

    def normalised(self, params):
        # pbrt-v4's Sphere: zmin and zmax default to -radius and radius, are ordered and clamped
        # to [-radius, radius]; phimax is clamped to [0, 360]
        radius, z0, z1, phi_max = params
        z0 = -radius if z0 is None else z0
        z1 = radius if z1 is None else z1
        clamp = lambda z: min(max(z, -abs(radius)), abs(radius))      # noqa: E731
        return radius, clamp(min(z0, z1)), clamp(max(z0, z1)), min(max(phi_max, 0.0), 2 * math.pi)

    def from_pbrt(self, params):
        """pbrt-v4's sphere with z turned round (turned_z), which is also the sphere range's uv
        where it is whole."""
        return (*turned_z(params), TextureUV.KIND)

    def check(self, params):
        radius, z_min, z_max, phi_max = params
        if not radius > 0:
            return f"radius must be positive, got {radius:g}"
        if not z_max > z_min:
            return f"z_min and z_max must leave a slice of the sphere in [-{radius:g}, {radius:g}], got {z_min:g} to {z_max:g}"
        if not 0 < phi_max <= 2 * math.pi:
            return f"phi_max must be in (0, 360] degrees, got {math.degrees(phi_max):g}"
        return None

    def object_bounds(self, params):
        radius, z_min, z_max, _ = params
        return np.array([-radius, -radius, z_min]), np.array([radius, radius, z_max])

    def area(self, params):
        radius, z_min, z_max, phi_max = params
        return phi_max * radius * (z_max - z_min)

    def object_normals(self, params, n):
        # a spiral of points even over the area: z uniform (Archimedes), the golden angle round
        radius, z_min, z_max, phi_max = params
        z = (z_min + (np.arange(n) + 0.5) / n * (z_max - z_min)) / radius
        phi = (np.arange(n) * GOLDEN_ANGLE) % (2 * math.pi) * phi_max / (2 * math.pi)
        ring = np.sqrt(np.maximum(0.0, 1 - z * z))
        return np.column_stack([ring * np.cos(phi), ring * np.sin(phi), z])

    def normal_cone(self, params):
        return np.array([0.0, 0.0, 1.0]), -1.0        # pbrt-v4: DirectionCone::EntireSphere

    def from_mitsuba(self, values, to_world, where):
        """Mitsuba 3's sphere (src/shapes/sphere.cpp): to_world translate(center) scale(radius),
        kept round whatever it is (update(): centre its image of the origin, radius the length of
        its image of (1, 0, 0), a warning where it shears or scales unevenly), normals outwards
        unless flip_normals, whatever the handedness. Its uv, (phi / 2 pi, theta / pi) of the
        point taken back to its object's space, are pbrt's with z turned round; the round
        sphere's frame is the rotation of to_world's polar decomposition."""
        m = np.asarray(to_world, np.float64)
        linear = m[:3, :3] * float(values["radius"])
        centre = m[:3, :3] @ np.asarray(values["center"], np.float64) + m[:3, 3]
        radius = float(np.linalg.norm(linear[:, 0]))
        if not (radius > 0 and abs(np.linalg.det(m[:3, :3])) > 0):
            return (radius, -radius, radius, 2 * math.pi), np.eye(4), TextureUV.KIND, False
        u, s, vt = np.linalg.svd(linear)
        if not np.allclose(s, s[0], rtol=1e-5):
            warn(f"{where}: a sphere whose to_world shears or scales unevenly; Mitsuba 3 renders it round, "
                 f"of radius |to_world (1, 0, 0)| = {radius:.4g}, and so does pathtrace")
        world = np.eye(4)
        world[:3, :3] = radius * (u @ vt)
        world[:3, 3] = centre
        return (1.0, -1.0, 1.0, 2 * math.pi), np.linalg.inv(m) @ world @ TURN_Z, TextureUV.KIND, bool(values["flip_normals"])

    @staticmethod
    def fast_range(shape, reads_frame):
        """(centre, radius) of the sphere range (kernels/shapes/sphere_range.cl) that renders the
        analytic sphere `shape` alike, or None: a whole sphere facing outwards under a
        similarity, whose rotation is TURN_Z where its material reads texture coordinates or
        tangents (the range's are Mitsuba's about the world's axes, which from_mitsuba and
        from_pbrt give an unrotated sphere).
        (Two cores, 2026-11-29: every sphere as this kind made simple-diffuse 3-5 times
        slower; docs/notes/performance-2026-11.md.)"""
        radius, z_min, z_max, phi_max = shape.params
        if shape.flip or shape.texture_uv is not TextureUV.KIND or z_min > -radius or z_max < radius or phi_max < 2 * math.pi:
            return None
        m = np.asarray(shape.to_world, np.float64)
        scale = float(np.linalg.norm(m[:3, 0]))
        rotation = m[:3, :3] / scale
        if not np.allclose(rotation.T @ rotation, np.eye(3), rtol=0, atol=1e-6):
            return None
        if reads_frame and not np.allclose(rotation, TURN_Z[:3, :3], rtol=0, atol=1e-6):
            return None
        return m[:3, 3].copy(), radius * scale
