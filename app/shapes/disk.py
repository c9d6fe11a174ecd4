"""The disk (kernels/shapes/disk.cl): pbrt-v4's `disk` (radius, innerradius, height, phimax),
texture coordinates (u, 1 - v), and Mitsuba 3's `disk` (the unit disk, texture coordinates
(r, phi / 2 pi)): app/shapes/texture_uv.py."""

import math

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.shapes.shape import Quadric
from pathtrace.shapes.texture_uv import TextureUV


class Disk(Quadric):
    name = "disk"
    formats = {"mitsuba": "disk", "pbrt": "disk"}
    doc = ("An annulus sector at z = height facing +z; uv (phi / phi_max, (radius - r) / (radius - "
           "inner_radius)), pbrt-v4's, whose texture coordinates the pbrt-v4 reader makes (u, 1 - v) "
           "(texture_uv). Mitsuba's is the unit disk, texture coordinates (r, phi / 2 pi).")
    parameters = (Parameter("radius", "number", 1.0, doc="outer radius", pbrt="radius"),
                  Parameter("inner_radius", "number", 0.0, doc="inner radius: an annulus", pbrt="innerradius"),
                  Parameter("height", "number", 0.0, doc="its plane's z in object space", pbrt="height"),
                  Parameter("phi_max", "number", 360.0, pbrt="phimax",
                            doc="the angle it spans, degrees (more is 360: pbrt-v4 clamps it)"))
    angles = ("phi_max",)
    mitsuba_parameters = (Parameter(None, "bool", doc="its front turned round", mitsuba="flip_normals",
                                    mitsuba_default=False),)
    examples = ((1.0, 0.0, 0.0, 2 * math.pi), (1.5, 0.6, 0.25, math.radians(250)))

    def normalised(self, params):
        radius, inner, height, phi_max = params
        return radius, inner, height, min(max(phi_max, 0.0), 2 * math.pi)    # pbrt-v4 clamps phimax to [0, 360]

    def from_pbrt(self, params):
        """pbrt-v4's disk as it is, texture coordinates (u, 1 - v) (TextureUV.PBRT): its v =
        (radius - r) / (radius - innerradius) (src/pbrt/shapes.h, Disk::InteractionFromIntersection)
        runs along the radius, which no mirror of the plane turns round, as turned_z turns a
        sphere's and a cylinder's."""
        return params, np.eye(4), TextureUV.PBRT

    def from_mitsuba(self, values, to_world, where):
        """Mitsuba 3's disk is the unit disk facing +z of its to_world, its texture coordinates
        (r, phi / 2 pi) (src/shapes/disk.cpp), flip_normals turning its normal."""
        return (1.0, 0.0, 0.0, 2 * math.pi), np.eye(4), TextureUV.MITSUBA_DISK, bool(values["flip_normals"])

    def own_problem(self, params):
        radius, inner = params[:2]
        if not 0 <= inner < radius:
            return f"inner_radius must be at least 0 and below the radius {radius:g}, got {inner:g}"
        return None

    def z_range(self, params):
        return params[2], params[2]

    def area(self, params):
        radius, inner, _, phi_max = params
        return 0.5 * phi_max * (radius ** 2 - inner ** 2)

    def object_normals(self, params, n):
        return np.tile([0.0, 0.0, 1.0], (n, 1))

    def normal_cone(self, params):
        return np.array([0.0, 0.0, 1.0]), 1.0
