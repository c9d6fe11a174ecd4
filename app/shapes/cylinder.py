"""The cylinder (kernels/shapes/cylinder.cl), without caps: pbrt-v4's `cylinder` (radius, zmin,
zmax, phimax) and Mitsuba 3's `cylinder` (radius, p0, p1, flip_normals)."""

import math

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.shapes.shape import Quadric, turned_z
from pathtrace.shapes.texture_uv import TextureUV


class Cylinder(Quadric):
    name = "cylinder"
    formats = {"mitsuba": "cylinder", "pbrt": "cylinder"}
    doc = ("The wall at distance radius from the z axis, z_min to z_max, no caps, facing away from "
           "the axis; uv (phi / phi_max, (z - z_min) / (z_max - z_min)). Mitsuba's runs from p0 to p1.")
    parameters = (Parameter("radius", "number", 1.0, doc="distance from the z axis", pbrt="radius"),
                  Parameter("z_min", "number", -1.0, pbrt="zmin",
                            doc="one end on the z axis (the two in either order: pbrt-v4 orders them)"),
                  Parameter("z_max", "number", 1.0, doc="the other end on the z axis", pbrt="zmax"),
                  Parameter("phi_max", "number", 360.0, pbrt="phimax",
                            doc="the angle it spans, degrees (more is 360: pbrt-v4 clamps it)"))
    angles = ("phi_max",)
    mitsuba_parameters = (Parameter(None, "number", doc="radius", mitsuba="radius", mitsuba_default=1.0),
                          Parameter(None, "point", doc="start of the axis", mitsuba="p0", mitsuba_default=(0.0, 0.0, 0.0)),
                          Parameter(None, "point", doc="end of the axis", mitsuba="p1", mitsuba_default=(0.0, 0.0, 1.0)),
                          Parameter(None, "bool", doc="its front turned round", mitsuba="flip_normals",
                                    mitsuba_default=False))
    examples = ((1.0, -1.0, 1.0, 2 * math.pi), (0.5, 0.2, 1.4, math.radians(200)))

    def normalised(self, params):
        # pbrt-v4 (Cylinder::Create, shapes.cpp) orders zmin and zmax and clamps phimax to [0, 360]
        radius, z0, z1, phi_max = params
        return radius, min(z0, z1), max(z0, z1), min(max(phi_max, 0.0), 2 * math.pi)

    def own_problem(self, params):
        z_min, z_max = params[1:3]
        return None if z_max > z_min else f"z_max must be above z_min, got {z_min:g} to {z_max:g}"

    def z_range(self, params):
        return params[1], params[2]

    def area(self, params):
        radius, z_min, z_max, phi_max = params
        return (z_max - z_min) * radius * phi_max

    def object_normals(self, params, n):
        phi = (np.arange(n) + 0.5) / n * params[3]
        return np.column_stack([np.cos(phi), np.sin(phi), np.zeros(n)])

    def normal_cone(self, params):
        return np.array([0.0, 0.0, 1.0]), -1.0        # pbrt-v4: DirectionCone::EntireSphere

    def from_pbrt(self, params):
        """pbrt-v4's cylinder with z turned round (turned_z): its texture v = 1 - pbrt's v."""
        return (*turned_z(params), TextureUV.KIND)

    def from_mitsuba(self, values, to_world, where):
        """Mitsuba 3's cylinder (src/shapes/cylinder.cpp): the unit cylinder, z in [0, 1] and a
        whole turn, under translate(p0) to_frame(p1 - p0) scale(radius, radius, |p1 - p0|), its
        frame's x and y those of Mitsuba's coordinate_system (Duff et al., "Building an
        Orthonormal Basis, Revisited", JCGT 6(1), 2017), which place phi = 0. Its normal is the
        cross product of its world tangents, turned by flip_normals: under a transform that
        swaps handedness, the opposite of the object normal moved."""
        radius = float(values["radius"])
        p0, p1 = np.asarray(values["p0"], np.float64), np.asarray(values["p1"], np.float64)
        length = float(np.linalg.norm(p1 - p0))
        if not (radius > 0 and length > 0):
            return (radius, 0.0, length, 2 * math.pi), np.eye(4), TextureUV.KIND, False
        n = (p1 - p0) / length
        sign = math.copysign(1.0, n[2])
        a = -1.0 / (sign + n[2])
        b = n[0] * n[1] * a
        s = np.array([1.0 + sign * n[0] ** 2 * a, sign * b, -sign * n[0]])
        t = np.array([b, sign + n[1] ** 2 * a, -n[1]])
        local = np.eye(4)
        local[:3, :3] = np.column_stack([s, t, n]) @ np.diag([radius, radius, length])
        local[:3, 3] = p0
        flip = bool(values["flip_normals"]) != (np.linalg.det(np.asarray(to_world, np.float64)[:3, :3]) < 0)
        return (1.0, 0.0, 1.0, 2 * math.pi), local, TextureUV.KIND, flip
