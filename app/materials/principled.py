"""Disney's principled BSDF as Mitsuba 3 implements it (its `principled`): a diffuse lobe with
retro-reflection and fake subsurface, sheen, an anisotropic GGX specular lobe blending dielectric
and metal, GGX transmission and a GTR1 clearcoat, each weighted by artist-friendly parameters in
[0, 1]; kernels/bsdfs/principled.cl."""

import numpy as np

from pathtrace.materials.bsdf import TRANSMISSIVE, BSDFType, Param
from pathtrace.textures.texture import Texture
from pathtrace.device.slots import read_slot


def _unit(name, default, slot, doc):
    return Param(name, "number", default=default, high=1.0, slot=slot, doc=doc)


def eta_of_specular(specular):
    """The IOR whose normal-incidence reflectance is 0.08 specular (Burley 2012: specular 0.5 is
    4 %, an IOR of 1.5), as Mitsuba converts it."""
    return 2.0 / (1.0 - np.sqrt(0.08 * specular)) - 1.0


class Principled(BSDFType):
    name = "principled"
    formats = {"mitsuba": "principled"}
    examples = ({"base_color": [0.8, 0.3, 0.1], "roughness": 0.3, "metallic": 0.4, "spec_tint": 0.6,
                 "sheen": 0.8, "clearcoat": 0.9, "clearcoat_gloss": 0.7},
                {"base_color": [0.95, 0.7, 0.3], "roughness": 0.5, "anisotropic": 0.8, "metallic": 1.0},
                {"base_color": [0.9, 0.8, 0.6], "roughness": 0.2, "spec_trans": 0.8, "eta": 1.45},
                {"base_color": [0.3, 0.6, 0.2], "roughness": 0.6, "spec_trans": 0.5, "metallic": 0.2,
                 "specular": 0.7, "clearcoat": 0.5, "flatness": 0.6, "anisotropic": 0.4, "sheen": 0.5,
                 "clearcoat_sampling_rate": 3.0, "diffuse_reflectance_sampling_rate": 0.5})
    reciprocal = False
    params = (
        Param("base_color", "color", default=0.5, high=1.0, slot="p0.xyz",
              doc="the colour of the diffuse lobe, the metal, and the tints"),
        _unit("roughness", 0.5, "p0.w", "the specular lobes' roughness (GGX alpha = roughness^2)"),
        _unit("metallic", 0.0, "p1.x", "0 a dielectric, 1 a metal coloured by base_color"),
        _unit("spec_tint", 0.0, "p1.y", "how far the dielectric reflection leans towards base_color"),
        _unit("anisotropic", 0.0, "p1.z", "the specular roughness's anisotropy, stretched along dp/du"),
        _unit("sheen", 0.0, "p1.w", "the grazing sheen lobe's strength (cloth)"),
        _unit("sheen_tint", 0.0, "p2.x", "how far the sheen leans towards base_color"),
        _unit("clearcoat", 0.0, "p2.y", "the GTR1 clearcoat lobe's strength"),
        _unit("clearcoat_gloss", 0.0, "p2.z", "the clearcoat's gloss: 0 (alpha 0.1) to 1 (alpha 0.001)"),
        _unit("spec_trans", 0.0, "p2.w", "the share of the dielectric that transmits (glass at 1)"),
        Param("eta", "number", default=float(eta_of_specular(0.5)), low=1.0, high=10.0, slot="table[0]",
              constant=True, doc="the IOR inside over outside; or give specular"),
        Param("specular", "number", default=0.5, high=1.0, into="eta",
              doc="the dielectric's reflectance at normal incidence over 0.08 (0.5: 4 %), instead of eta"),
        Param("flatness", "number", default=0.0, high=1.0, slot="table[1]", constant=True,
              doc="the diffuse lobe's blend towards Hanrahan-Krueger's fake subsurface (a constant)"),
        Param("main_specular_sampling_rate", "number", default=1.0, high=1e3, slot="table[2]", constant=True,
              doc="the specular lobes' weight in the choice of a lobe to sample"),
        Param("clearcoat_sampling_rate", "number", default=1.0, high=1e3, slot="table[3]", constant=True,
              doc="the clearcoat's weight in that choice"),
        Param("diffuse_reflectance_sampling_rate", "number", default=1.0, high=1e3, slot="table[4]", constant=True,
              doc="the diffuse lobe's weight in that choice"),
    )
    doc = ("Disney's principled BSDF as Mitsuba 3 has it (Burley 2012, 2015): diffuse with "
           "retro-reflection, sheen, anisotropic GGX specular, metal, GGX transmission, GTR1 clearcoat")
    variant_defines = ("ANISOTROPIC",)

    def resolve(self, values):
        values = super().resolve(values)
        if "specular" in values:
            if "eta" in values:
                raise ValueError("give eta or specular, not both (Mitsuba refuses both too)")
            specular = values.pop("specular")
            # Mitsuba keeps a transmitting material's IOR off 1, where it would not refract
            values["eta"] = float(eta_of_specular(max(specular, 1e-3) if self.transmits(values) else specular))
        elif self.transmits(values) and values.get("eta") == 1.0:
            values["eta"] = 1.001
        return values

    def transmits(self, values):
        spec_trans = values.get("spec_trans", 0.0)
        return isinstance(spec_trans, Texture) or bool(np.any(np.asarray(spec_trans) > 0))

    def defines(self, rows):
        anisotropic = read_slot(rows, self.slots()["anisotropic"])
        return ("ANISOTROPIC",) if np.any((anisotropic != 0) | (rows["textures"] >= 0)) else ()

    def row_flags(self, values, n):
        return np.where(np.broadcast_to(values["spec_trans"] > 0, n), TRANSMISSIVE, 0).astype(np.int32)

    def continuation(self, values):
        # any value in (0, 1] is unbiased: the diffuse albedo, or more where light is specular
        diffuse = np.max(values["base_color"], axis=-1) * (1.0 - values["metallic"]) * (1.0 - values["spec_trans"])
        return np.clip(diffuse + values["metallic"] + values["spec_trans"] + 0.04, 0.1, 1.0)
