"""pbrt-v4's layered materials: `coateddiffuse`, a Lambertian base under a smooth or rough
dielectric coating with a layer of medium between them, evaluated by random walks between the
layers (kernels/bsdfs/coateddiffuse.cl), with pbrt-v4's parameters and defaults."""

import numpy as np

from pathtrace.materials.bsdf import BSDFType, Param

MAX_WALK_DEPTH = 100      # maxdepth: events per random walk
MAX_WALKS = 16            # nsamples: walks per estimate


class CoatedDiffuse(BSDFType):
    name = "coateddiffuse"
    params = (
        Param("reflectance", "color", default=0.5, high=1.0, doc="the base's albedo", slot="p0.xyz"),
        Param("alpha", "number", default=0.0, high=1.0,
              doc="the coating's GGX roughness (pbrt's roughness, remapped or not); 0: smooth"),
        Param("eta", "number", default=1.5, low=1.0001, high=10.0, doc="the coating's IOR"),
        Param("thickness", "number", default=0.01, low=1e-6, high=1e3,
              doc="the layer between coating and base, in units of its extinction (1 per unit)"),
        Param("albedo", "color", default=0.0, high=1.0,
              doc="the layer's single-scattering albedo; 0: it only absorbs"),
        Param("g", "number", default=0.0, low=-0.999, high=0.999,
              doc="the layer's Henyey-Greenstein phase function's mean cosine"),
        Param("maxdepth", "number", default=10, low=1, high=MAX_WALK_DEPTH, doc="events per random walk"),
        Param("nsamples", "number", default=1, low=1, high=MAX_WALKS, doc="random walks per estimate"),
    )
    doc = ("pbrt-v4's coateddiffuse: a diffuse base under a smooth or rough dielectric coating, "
           "light followed between them by random walks (Guo et al. 2018)")

    def check(self, values):
        for name in ("maxdepth", "nsamples"):
            if np.any(values[name] != np.round(values[name])):
                return f"{name}: must be a whole number, got {np.ravel(values[name])[0]:g}"
        return None

    def pack(self, values, rows):
        rows["p0"][:, :3] = values["reflectance"]
        rows["p0"][:, 3] = values["alpha"]
        rows["p1"][:, 0] = values["eta"]
        rows["p1"][:, 1] = values["thickness"]
        rows["p1"][:, 2] = values["g"]
        rows["p1"][:, 3] = values["maxdepth"]
        rows["p2"][:, :3] = values["albedo"]
        rows["p2"][:, 3] = values["nsamples"]

    def unpack(self, row):
        return {"reflectance": row["p0"][:3].copy(), "alpha": float(row["p0"][3]), "eta": float(row["p1"][0]),
                "thickness": float(row["p1"][1]), "g": float(row["p1"][2]), "maxdepth": float(row["p1"][3]),
                "albedo": row["p2"][:3].copy(), "nsamples": float(row["p2"][3])}

    def continuation(self, values):
        return np.maximum(np.max(values["reflectance"], axis=-1), 0.1)
