"""Plastics: a diffuse base under a smooth or a rough (GGX or Beckmann) dielectric coating
(Mitsuba 3's `plastic` and `roughplastic`). roughplastic's slots extend plastic's, which
kernels/coating.cl reads for both."""

import numpy as np

from pathtrace.materials.bsdf import BSDFType, Param
from pathtrace.materials.dielectric import check_interface
from pathtrace.materials.microfacet import DISTRIBUTION, GGX_PARAMS, check_distribution, rough_coating
from pathtrace.materials.optics import IOR, diffuse_fresnel_reflectance
from pathtrace.device.slots import Slot, read_slot, write_slot


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
        Param("ext_ior", "number", default=1.000277, low=1.0, high=10.0, names=IOR, slot="p2.z", constant=True,
              doc="IOR outside"),
        Param("nonlinear", "bool", default=False, slot="p2.y", constant=True,
              doc="account for the colour shift of light bouncing inside the coating"),
    )
    derived = (
        Slot("eta", "p0.w", "int_ior / ext_ior, the coating's relative IOR"),
        Slot("f_int", "p1.w", "the coating's reflectance seen from inside, averaged over the base's "
                              "cosine-weighted light (pack_coating)"),
        Slot("specular_share", "p2.x", "mean(specular_reflectance) / (mean(diffuse_reflectance) + "
                                       "mean(specular_reflectance)), 1 where both are 0: the specular "
                                       "lobe's share in the lobe choice, as Mitsuba's plastics"),
    )
    host_only = ("ext_ior",)      # with eta, int_ior for unpack; the kernels read eta
    doc = ("a diffuse base under a smooth dielectric coating: the coating's specular reflection "
           "plus the light it lets through to the base and back out")

    def check(self, values):
        return check_interface(values)

    def pack(self, values, rows):
        super().pack(values, rows)
        slots = self.slots()
        eta = np.broadcast_to(np.asarray(values["int_ior"], np.float64) / values["ext_ior"], len(rows))
        write_slot(rows, slots["eta"], eta)
        # lobe choice in the ratio of the mean reflectances, as Mitsuba's plastics
        d_mean, s_mean = np.mean(values["diffuse_reflectance"], axis=-1), np.mean(values["specular_reflectance"], axis=-1)
        write_slot(rows, slots["specular_share"],
                   np.where(d_mean + s_mean > 0, s_mean / np.maximum(d_mean + s_mean, 1e-30), 1.0))
        # the coating seen from inside, averaged over the base's cosine-weighted light
        self.pack_coating(values, eta, rows)

    def pack_coating(self, values, eta, rows):
        distinct, which = np.unique(eta, return_inverse=True)
        write_slot(rows, self.slots()["f_int"], np.array([diffuse_fresnel_reflectance(1.0 / e) for e in distinct])[which])

    def unpack(self, row):
        out = super().unpack(row)
        return {**out, "int_ior": float(read_slot(row, self.slots()["eta"])) * out["ext_ior"]}


class RoughPlastic(Plastic):
    name = "roughplastic"
    formats = {"mitsuba": "roughplastic"}
    examples = ({"diffuse_reflectance": [0.7, 0.3, 0.1], "alpha": 0.1, "int_ior": 1.5},
                {"diffuse_reflectance": [0.2, 0.9, 0.5], "alpha": 0.6, "nonlinear": True, "specular_reflectance": 0.7},
                {"diffuse_reflectance": [0.7, 0.3, 0.1], "alpha": 0.2, "distribution": "beckmann"})
    params = Plastic.params + GGX_PARAMS + (DISTRIBUTION,)
    derived = Plastic.derived + (
        Slot("signed_alpha", "p2.w", "alpha, negated for Beckmann"),
        Slot("transmittance", "table", "the rough coating's transmittance T(cos) from outside, at cos = "
                                      "(k / 15)^2 (microfacet.py: rough_coating)"),
    )
    reads_as = {"plastic": {name: name for name in Plastic().slots()}}      # kernels/coating.cl
    doc = ("a diffuse base under a rough (GGX or Beckmann) dielectric coating: the coating's glossy "
           "reflection plus the light it lets through to the base and back out")

    def check(self, values):
        return check_distribution(values) or super().check(values)

    variant_defines = ("BECKMANN",)

    def defines(self, rows):
        return ("BECKMANN",) if np.any(read_slot(rows, self.slots()["signed_alpha"]) < 0) else ()

    def pack(self, values, rows):
        write_slot(rows, self.slots()["signed_alpha"],
                   np.where(np.asarray(values["distribution"]) > 0.5, -1.0, 1.0) * values["alpha"])
        super().pack(values, rows)

    def pack_coating(self, values, eta, rows):
        """The rough coating's transmittance table and mean internal reflectance, once per
        distinct (alpha, eta, distribution)."""
        slots = self.slots()
        alpha = np.broadcast_to(read_slot(rows, slots["signed_alpha"]), len(rows))
        distinct, which = np.unique(np.stack([alpha, eta], axis=1), axis=0, return_inverse=True)
        for k, (a, e) in enumerate(distinct):
            table, inside = rough_coating(abs(float(a)), float(e), bool(a < 0))
            chosen = rows[which.reshape(-1) == k]
            write_slot(chosen, slots["transmittance"], table)
            write_slot(chosen, slots["f_int"], inside)
            rows[which.reshape(-1) == k] = chosen

    def unpack(self, row):
        signed_alpha = float(read_slot(row, self.slots()["signed_alpha"]))
        return {**super().unpack(row), "alpha": abs(signed_alpha), "distribution": 1.0 if signed_alpha < 0 else 0.0}
