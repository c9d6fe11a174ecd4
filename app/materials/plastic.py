"""Plastic: a diffuse base under a smooth dielectric coating (Mitsuba 3's `plastic`)."""

import numpy as np

from app.materials.bsdf import BSDFType, Param
from app.materials.dielectric import check_interface
from app.materials.optics import IOR, diffuse_fresnel_reflectance


class Plastic(BSDFType):
    name = "plastic"
    params = (
        Param("diffuse_reflectance", "color", default=0.5, high=1.0, doc="the base's albedo"),
        Param("specular_reflectance", "color", default=1.0, high=1.0,
              doc="factor on the coating's reflection"),
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
        eta = np.asarray(values["int_ior"], np.float64) / values["ext_ior"]
        eta = np.broadcast_to(eta, len(rows))
        d, s = values["diffuse_reflectance"], values["specular_reflectance"]
        rows["p0"][:, :3] = d
        rows["p0"][:, 3] = eta
        rows["p1"][:, :3] = s
        # the coating seen from inside, averaged over the base's cosine-weighted light
        distinct, which = np.unique(eta, return_inverse=True)
        rows["p1"][:, 3] = np.array([diffuse_fresnel_reflectance(1.0 / e) for e in distinct])[which]
        # lobe choice in the ratio of the mean reflectances, as Mitsuba's plastic
        d_mean, s_mean = np.mean(d, axis=-1), np.mean(s, axis=-1)
        rows["p2"][:, 0] = np.where(d_mean + s_mean > 0, s_mean / np.maximum(d_mean + s_mean, 1e-30), 1.0)
        rows["p2"][:, 1] = values["nonlinear"]
        rows["p2"][:, 2] = values["int_ior"]
        rows["p2"][:, 3] = values["ext_ior"]

    def unpack(self, row):
        return {"diffuse_reflectance": row["p0"][:3].copy(),
                "specular_reflectance": row["p1"][:3].copy(),
                "int_ior": float(row["p2"][2]), "ext_ior": float(row["p2"][3]),
                "nonlinear": bool(row["p2"][1])}
