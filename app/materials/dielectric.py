"""Glass: the smooth interface between two dielectrics (Fresnel reflection and refraction), a
rough one (Walter et al.'s microfacet model), and a thin sheet of glass (no refraction), with
Mitsuba 3's parameters."""

import math
from dataclasses import replace

import numpy as np

from pathtrace.materials.bsdf import DELTA, TRANSMISSIVE, BSDFType, Param
from pathtrace.materials.microfacet import (DISTRIBUTION, PBRT_REMAP, AnisotropicRoughness, anisotropic_params,
                                            check_distribution, pbrt_alphas, pbrt_rough, pbrt_roughness)
from pathtrace.materials.optics import IOR
from pathtrace.parameters import Parameter
from pathtrace.device.slots import read_slot

PBRT_ETA = Parameter(None, "color", spectrum="unbounded", pbrt="eta", pbrt_default=1.5,
                     doc="the inside's IOR over the outside's (a spectrum: its mean)")


def pbrt_eta(given: dict, name: str = "eta") -> float:
    """pbrt-v4's eta (a float, or a spectrum's mean), in [0.1, 10]. Raises ValueError."""
    eta = float(np.mean(given[name]))
    if not 0.1 <= eta <= 10 or not math.isfinite(eta):
        raise ValueError(f"{name}: must lie in [0.1, 10], got {eta:g}")
    return eta

def check_interface(values) -> str | None:
    """The two IORs of an interface (glass, a plastic's coating) must differ."""
    if np.any(values["int_ior"] == values["ext_ior"]):
        return "int_ior and ext_ior must differ (an interface of equal IORs is invisible)"
    return None


_DIELECTRIC_PARAMS = (
    Param("int_ior", "number", default=1.5046, low=1.0, high=10.0, names=IOR, slot="p0.x", constant=True,
          doc="IOR inside (the side opposite the normal): a number or a name such as bk7, water, "
              "diamond", pbrt_from="eta"),
    Param("ext_ior", "number", default=1.000277, low=1.0, high=10.0, names=IOR, slot="p0.y", constant=True,
          doc="IOR outside"),
    Param("specular_reflectance", "color", default=1.0, high=1.0, doc="factor on reflection", slot="p1.xyz"),
    Param("specular_transmittance", "color", default=1.0, high=1.0, doc="factor on transmission",
          slot="p2.xyz"),
)


class Dielectric(BSDFType):
    name = "dielectric"
    formats = {"mitsuba": "dielectric", "pbrt": "dielectric"}
    format_only = (PBRT_ETA, *pbrt_roughness(), PBRT_REMAP)
    examples = ({"int_ior": 1.5}, {"int_ior": "water", "specular_transmittance": [0.9, 0.7, 0.5]})
    params = _DIELECTRIC_PARAMS
    flags = DELTA | TRANSMISSIVE
    doc = "smooth glass: Fresnel reflection and refraction, total internal reflection"

    def check(self, values):
        return check_interface(values)

    def from_pbrt(self, values, given, warn):
        """pbrt-v4's dielectric (a roughdielectric, GGX, where rough) or thindielectric (which
        reads no roughness: thin glass is smooth); eta 1 is no surface (None). pbrt-v4's eta is
        the inside's IOR over the outside's, any positive value (its DielectricBxDF takes etap =
        eta or 1 / eta by the side wo is on): below 1 the outside is the denser, an air bubble
        in water."""
        eta = pbrt_eta(given)
        rough = pbrt_rough(pbrt_alphas(given)) if "roughness" in given else None
        if eta == 1.0:
            warn("a dielectric of eta 1 is invisible; pathtrace leaves the surface out")
            return None
        iors = {"int_ior": eta, "ext_ior": 1.0} if eta > 1 else {"int_ior": 1.0, "ext_ior": 1 / eta}
        return ("roughdielectric", {**iors, **rough}) if rough else (self.name, iors)


class ThinDielectric(Dielectric):
    name = "thindielectric"
    formats = {"mitsuba": "thindielectric", "pbrt": "thindielectric"}
    format_only = (PBRT_ETA,)
    examples = ({"int_ior": 1.5}, {"int_ior": "diamond", "specular_reflectance": 0.5})
    doc = ("a thin sheet of glass: light is reflected or passes straight through, with the "
           "sheet's inner reflections summed")


class RoughDielectric(AnisotropicRoughness, Dielectric):
    name = "roughdielectric"
    formats = {"mitsuba": "roughdielectric"}
    format_only = ()
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
