"""Plastics: a diffuse base under a smooth or a rough (GGX or Beckmann) dielectric coating
(Mitsuba 3's `plastic` and `roughplastic`; both pack the layout of kernels/coating.cl)."""

import numpy as np

from pathtrace.materials.bsdf import BSDFType, Param
from pathtrace.materials.dielectric import check_interface
from pathtrace.materials.microfacet import DISTRIBUTION, GGX_PARAMS, check_distribution, rough_coating
from pathtrace.materials.optics import IOR, diffuse_fresnel_reflectance


class Plastic(BSDFType):
    name = "plastic"
    formats = {"mitsuba": "plastic"}
    examples = ({"diffuse_reflectance": [0.7, 0.3, 0.1], "int_ior": 1.5},
                {"diffuse_reflectance": 0.9, "nonlinear": True, "int_ior": "diamond"})
    params = (
        Param("diffuse_reflectance", "color", default=0.5, high=1.0, doc="the base's albedo",
              slot="p0.xyz"),
        Param("specular_reflectance", "color", default=1.0, high=1.0,
              doc="factor on the coating's reflection", slot="p1.xyz"),
        Param("int_ior", "number", default=1.49, low=1.0, high=10.0, names=IOR,
              doc="the coating's IOR: a number or a name (default polypropylene)"),
        Param("ext_ior", "number", default=1.000277, low=1.0, high=10.0, names=IOR,
              doc="IOR outside"),
        Param("nonlinear", "bool", default=False,
              doc="account for the colour shift of light bouncing inside the coating"),
    )
    doc = ("a diffuse base under a smooth dielectric coating: the coating's specular reflection "
           "plus the light it lets through to the base and back out")

    def check(self, values):
        return check_interface(values)

    def pack(self, values, rows):
        eta = np.broadcast_to(np.asarray(values["int_ior"], np.float64) / values["ext_ior"], len(rows))
        d, s = values["diffuse_reflectance"], values["specular_reflectance"]
        rows["p0"][:, :3] = d
        rows["p0"][:, 3] = eta
        rows["p1"][:, :3] = s
        # lobe choice in the ratio of the mean reflectances, as Mitsuba's plastics
        d_mean, s_mean = np.mean(d, axis=-1), np.mean(s, axis=-1)
        rows["p2"][:, 0] = np.where(d_mean + s_mean > 0, s_mean / np.maximum(d_mean + s_mean, 1e-30), 1.0)
        rows["p2"][:, 1] = values["nonlinear"]
        rows["p2"][:, 2] = values["ext_ior"]
        # the coating seen from inside, averaged over the base's cosine-weighted light
        self.pack_coating(values, eta, rows)

    def pack_coating(self, values, eta, rows):
        distinct, which = np.unique(eta, return_inverse=True)
        rows["p1"][:, 3] = np.array([diffuse_fresnel_reflectance(1.0 / e) for e in distinct])[which]

    def unpack(self, row):
        ext_ior = float(row["p2"][2])
        return {"diffuse_reflectance": row["p0"][:3].copy(),
                "specular_reflectance": row["p1"][:3].copy(),
                "int_ior": float(row["p0"][3]) * ext_ior, "ext_ior": ext_ior,
                "nonlinear": bool(row["p2"][1])}


class RoughPlastic(Plastic):
    name = "roughplastic"
    formats = {"mitsuba": "roughplastic"}
    examples = ({"diffuse_reflectance": [0.7, 0.3, 0.1], "alpha": 0.1, "int_ior": 1.5},
                {"diffuse_reflectance": [0.2, 0.9, 0.5], "alpha": 0.6, "nonlinear": True, "specular_reflectance": 0.7},
                {"diffuse_reflectance": [0.7, 0.3, 0.1], "alpha": 0.2, "distribution": "beckmann"})
    params = Plastic.params + GGX_PARAMS + (DISTRIBUTION,)
    doc = ("a diffuse base under a rough (GGX or Beckmann) dielectric coating: the coating's glossy "
           "reflection plus the light it lets through to the base and back out")

    def check(self, values):
        return check_distribution(values) or super().check(values)

    variant_defines = ("BECKMANN",)

    def defines(self, rows):
        return ("BECKMANN",) if np.any(rows["p2"][:, 3] < 0) else ()

    def pack(self, values, rows):
        # alpha, negated for Beckmann (kernels/bsdfs/roughplastic.cl)
        rows["p2"][:, 3] = np.where(np.asarray(values["distribution"]) > 0.5, -1.0, 1.0) * values["alpha"]
        super().pack(values, rows)

    def pack_coating(self, values, eta, rows):
        """The rough coating's transmittance table and mean internal reflectance, once per
        distinct (alpha, eta, distribution)."""
        alpha = np.broadcast_to(rows["p2"][:, 3], len(rows))
        distinct, which = np.unique(np.stack([alpha, eta], axis=1), axis=0, return_inverse=True)
        for k, (a, e) in enumerate(distinct):
            table, inside = rough_coating(abs(float(a)), float(e), bool(a < 0))
            rows["table"][which.reshape(-1) == k] = table
            rows["p1"][which.reshape(-1) == k, 3] = inside

    def unpack(self, row):
        return {**super().unpack(row), "alpha": abs(float(row["p2"][3])),
                "distribution": 1.0 if row["p2"][3] < 0 else 0.0}
