"""Metals: a smooth conductor (a mirror with the Fresnel reflectance of a complex IOR) and a
rough one (the GGX or Beckmann microfacet model), with Mitsuba 3's parameters."""

from dataclasses import replace

import numpy as np

from pathtrace.materials.bsdf import DELTA, BSDFType, Param
from pathtrace.materials.microfacet import (DISTRIBUTION, PBRT_REMAP, AnisotropicRoughness, anisotropic_params,
                                            check_distribution, pbrt_alphas, pbrt_rough, pbrt_roughness)
from pathtrace.materials.optics import CONDUCTORS
from pathtrace.parameters import Parameter
from pathtrace.device.slots import read_slot

# a reflectance r becomes k = 2 sqrt(r) / sqrt(1 - r) (pbrt_metal): r at most 100^2 / (4 + 100^2),
# 0.9996, keeps k within the conductor's bound of 100
MAX_REFLECTANCE = 100.0 ** 2 / (4 + 100.0 ** 2)


def pbrt_metal_params(prefix: str = "") -> tuple:
    """pbrt-v4's metal (a conductor's; a coatedconductor's prefixed `conductor.`): eta and k,
    copper's by default, or instead a reflectance (pbrt_metal reads them)."""
    return (Parameter(None, "color", spectrum="unbounded", pbrt=prefix + "eta", pbrt_default="metal-Cu-eta",
                      doc="real part of the complex IOR"),
            Parameter(None, "color", spectrum="unbounded", pbrt=prefix + "k", pbrt_default="metal-Cu-k",
                      doc="imaginary part"),
            Parameter(None, "color", pbrt="reflectance", doc="instead of eta and k: eta 1, k = 2 sqrt(r) / sqrt(1 - r)"))


def pbrt_metal(given: dict, prefix: str = "") -> dict:
    """The eta and k of pbrt_metal_params(prefix)'s values, by pbrt-v4's names: a reflectance r is
    the Fresnel reflectance of eta 1 and k = 2 sqrt(r) / sqrt(1 - r) (src/pbrt/materials.cpp)."""
    if given["reflectance"] is not None:
        r = np.clip(given["reflectance"], 0.0, MAX_REFLECTANCE)
        return {"eta": np.ones(3), "k": 2 * np.sqrt(r) / np.sqrt(1 - r)}
    from pathtrace.scene.spectra import named_spectrum     # pathtrace.scene imports the materials
    return {name: named_spectrum(v)[0] if isinstance(v, str) else v
            for name, v in (("eta", given[prefix + "eta"]), ("k", given[prefix + "k"]))}

_CONDUCTOR_PARAMS = (
    Param("material", "name", default="none", names=CONDUCTORS,
          doc="a named metal (Mitsuba's: Au, Ag, Cu, Al, Cr, ... or gold, silver, copper, "
              "aluminium), or none, a perfect mirror; instead of eta and k"),
    Param("eta", "color", default=0.0, high=100.0, doc="real part of the complex IOR", slot="p0.xyz",
          pbrt_from="eta"),
    Param("k", "color", default=1.0, high=100.0, doc="imaginary part (absorption) of the IOR", slot="p1.xyz",
          pbrt_from="k or reflectance"),
    Param("specular_reflectance", "color", default=1.0, high=1.0,
          doc="a factor on the reflectance (not physical; Mitsuba's)", slot="p2.xyz"),
)


METAL_PARAMS = _CONDUCTOR_PARAMS[:3]      # a metal's: a named one, or eta and k


def resolve_metal(values: dict) -> dict:
    """A named metal ('material') turned into its eta and k."""
    if "material" in values:
        if "eta" in values or "k" in values:
            raise ValueError("give either 'material' or 'eta' and 'k', not both")
        name = values.pop("material")
        if name not in CONDUCTORS:
            raise ValueError(f"material: unknown conductor {name!r} (known: {', '.join(sorted(CONDUCTORS))})")
        values["eta"], values["k"] = CONDUCTORS[name]
    return values


class Conductor(BSDFType):
    name = "conductor"
    formats = {"mitsuba": "conductor", "pbrt": "conductor"}
    format_only = pbrt_metal_params() + pbrt_roughness() + (PBRT_REMAP,)
    examples = ({"material": "Au"}, {"eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.2], "specular_reflectance": 0.8})
    params = _CONDUCTOR_PARAMS
    flags = DELTA
    doc = "smooth metal: a mirror whose reflectance is the conductor Fresnel equations'"

    def resolve(self, values):
        return resolve_metal(super().resolve(values))

    def from_pbrt(self, values, given, warn):
        """pbrt-v4's conductor: smooth, or a roughconductor (GGX) where rough."""
        rough = pbrt_rough(pbrt_alphas(given))
        return ("roughconductor", {**pbrt_metal(given), **rough}) if rough else ("conductor", pbrt_metal(given))


class RoughConductor(AnisotropicRoughness, Conductor):
    name = "roughconductor"
    formats = {"mitsuba": "roughconductor"}
    format_only = ()
    examples = ({"material": "Au", "alpha": 0.15}, {"alpha": 0.5}, {"material": "Al", "alpha": 0.9},
                {"material": "Au", "alpha": 0.1, "distribution": "beckmann"}, {"alpha": 0.6, "distribution": "beckmann"},
                {"material": "Cu", "alpha": 0.05, "alpha_v": 0.4, "distribution": "ggx"},
                {"alpha": 0.5, "alpha_v": 0.1, "distribution": "beckmann"})
    params = _CONDUCTOR_PARAMS + anisotropic_params("p0.w", "p1.w") + (replace(DISTRIBUTION, slot="p2.w", constant=True),)
    flags = 0
    doc = ("rough metal: the GGX or Beckmann microfacet BRDF with Smith's separable shadowing, "
           "isotropic or anisotropic, sampled by visible normals (Heitz 2018; Jakob 2014)")

    def check(self, values):
        return check_distribution(values)

    variant_defines = ("BECKMANN",) + AnisotropicRoughness.variant_defines

    def defines(self, rows):
        slots = self.slots()
        return ((("BECKMANN",) if np.any(read_slot(rows, slots["distribution"]) > 0.5) else ())
                + (("ANISOTROPIC",) if self.anisotropic(rows, read_slot(rows, slots["alpha"]),
                                                        read_slot(rows, slots["alpha_v"])) else ()))
