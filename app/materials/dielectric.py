"""Glass: the smooth interface between two dielectrics (Fresnel reflection and refraction), a
rough one (Walter et al.'s microfacet model), and a thin sheet of glass (no refraction), with
Mitsuba 3's parameters."""

from dataclasses import replace

import numpy as np

from pathtrace.materials.bsdf import DELTA, TRANSMISSIVE, BSDFType, Param
from pathtrace.materials.microfacet import DISTRIBUTION, AnisotropicRoughness, anisotropic_params, check_distribution
from pathtrace.materials.optics import IOR
from pathtrace.device.slots import read_slot

def check_interface(values) -> str | None:
    """The two IORs of an interface (glass, a plastic's coating) must differ."""
    if np.any(values["int_ior"] == values["ext_ior"]):
        return "int_ior and ext_ior must differ (an interface of equal IORs is invisible)"
    return None


_DIELECTRIC_PARAMS = (
    Param("int_ior", "number", default=1.5046, low=1.0, high=10.0, names=IOR, slot="p0.x", constant=True,
          doc="IOR inside (the side opposite the normal): a number or a name such as bk7, water, "
              "diamond"),
    Param("ext_ior", "number", default=1.000277, low=1.0, high=10.0, names=IOR, slot="p0.y", constant=True,
          doc="IOR outside"),
    Param("specular_reflectance", "color", default=1.0, high=1.0, doc="factor on reflection", slot="p1.xyz"),
    Param("specular_transmittance", "color", default=1.0, high=1.0, doc="factor on transmission",
          slot="p2.xyz"),
)


class Dielectric(BSDFType):
    name = "dielectric"
    formats = {"mitsuba": "dielectric"}
    examples = ({"int_ior": 1.5}, {"int_ior": "water", "specular_transmittance": [0.9, 0.7, 0.5]})
    params = _DIELECTRIC_PARAMS
    flags = DELTA | TRANSMISSIVE
    doc = "smooth glass: Fresnel reflection and refraction, total internal reflection"

    def check(self, values):
        return check_interface(values)


class ThinDielectric(Dielectric):
    name = "thindielectric"
    formats = {"mitsuba": "thindielectric"}
    examples = ({"int_ior": 1.5}, {"int_ior": "diamond", "specular_reflectance": 0.5})
    doc = ("a thin sheet of glass: light is reflected or passes straight through, with the "
           "sheet's inner reflections summed")


class RoughDielectric(AnisotropicRoughness, Dielectric):
    name = "roughdielectric"
    formats = {"mitsuba": "roughdielectric"}
    examples = ({"alpha": 0.1, "int_ior": 1.5}, {"alpha": 0.5, "int_ior": "water"},
                {"alpha": 0.3, "int_ior": 1.5, "distribution": "beckmann"},
                {"alpha": 0.8, "int_ior": "diamond", "distribution": "beckmann"},
                {"alpha": 0.4, "alpha_v": 0.08, "int_ior": 1.5, "distribution": "ggx"})
    reciprocal = False
    params = _DIELECTRIC_PARAMS + anisotropic_params("p0.z", "p1.w") + (replace(DISTRIBUTION, slot="p0.w", constant=True),)
    flags = TRANSMISSIVE
    doc = ("rough glass: reflection and refraction by GGX or Beckmann microfacets (Walter et al. "
           "2007), sampled by the normals visible from the outgoing direction")

    def check(self, values):
        return check_distribution(values) or check_interface(values)

    variant_defines = ("BECKMANN",) + AnisotropicRoughness.variant_defines

    def defines(self, rows):
        slots = self.slots()
        return ((("BECKMANN",) if np.any(read_slot(rows, slots["distribution"]) > 0.5) else ())
                + (("ANISOTROPIC",) if self.anisotropic(rows, read_slot(rows, slots["alpha"]),
                                                        read_slot(rows, slots["alpha_v"])) else ()))
