"""The report's materials: black (an emitter's surface), Lambertian diffuse, modified Phong; and
null, no surface at all."""

import numpy as np

from pathtrace.materials.bsdf import NULL, BSDFType, Param, check_sum_at_most_one, pbrt_clamped
from pathtrace.device.slots import Slot, read_slot, write_slot


class Black(BSDFType):
    name = "black"
    examples = ({},)
    doc = "reflects nothing; with Le an emitter (the `emitter` type of scene files)"
    kernel = False

    def pack(self, values, rows):
        pass

    def unpack(self, row):
        return {}


class Null(BSDFType):
    name = "null"
    examples = ({},)
    doc = ("no surface: paths and shadow rays cross it unchanged, and it counts as no bounce; with "
           "media, the boundary of a medium (Mitsuba 3's null BSDF, pbrt-v4's interface material)")
    kernel = False
    flags = NULL
    formats = {"mitsuba": "null"}

    def pack(self, values, rows):
        pass

    def unpack(self, row):
        return {}


class Diffuse(BSDFType):
    name = "diffuse"
    examples = ({"rho_d": [0.8, 0.5, 0.2]},)
    formats = {"mitsuba": "diffuse", "pbrt": "diffuse"}
    # (low and high are integers for Mitsuba's message: "a reflectance must lie in [0, 1]")
    params = (Param("rho_d", "color", low=0, high=1, doc="albedo", slot="p0.xyz", mitsuba="reflectance",
                    mitsuba_default=0.5, pbrt="reflectance", pbrt_default=0.5, from_pbrt=pbrt_clamped),)
    doc = "Lambertian, f = rho_d / pi"

    def continuation(self, values):
        return np.max(values["rho_d"], axis=-1)


class Phong(BSDFType):
    name = "phong"
    examples = ({"rho_d": 0.3, "rho_s": 0.6, "n": 20.0}, {"rho_d": 0.1, "rho_s": 0.9, "n": 200.0},
                {"rho_d": [0.9, 0.1, 0.2], "rho_s": [0.1, 0.9, 0.3], "n": 30.0})
    lobe_weights = True
    params = (Param("rho_d", "color", high=1.0, doc="diffuse albedo", slot="p0.xyz"),
              Param("rho_s", "color", default=0.0, high=1.0, doc="glossy albedo", slot="p1.xyz"),
              Param("n", "number", doc="Phong exponent", slot="p1.w"))
    # the lobes are chosen in the ratio max(rho_d) : max(rho_s), so that with Russian roulette
    # going on with max(rho_d) + max(rho_s) (continuation) every channel's weight stays <= 1
    derived = (Slot("diffuse_share", "p0.w", "max(rho_d) / (max(rho_d) + max(rho_s)), 1 where both are 0: "
                    "the probability of sampling the diffuse lobe"),
               Slot("glossy_share", "p2.x", "1 - diffuse_share: the probability of sampling the glossy lobe"))
    doc = ("modified Phong (Lafortune & Willems 1994), f = rho_d / pi + rho_s (n + 2) / (2 pi) "
           "cos^n(alpha); rho_d + rho_s <= 1 in each channel")

    def check(self, values):
        return check_sum_at_most_one(values, "rho_d", "rho_s")

    @staticmethod
    def lobe_albedos(values):
        return np.max(values["rho_d"], axis=-1), np.max(values["rho_s"], axis=-1)

    def pack(self, values, rows):
        super().pack(values, rows)
        p_d, p_s = self.lobe_albedos(values)
        total = p_d + p_s
        # a black Phong material never samples; give it a harmless diffuse choice
        diffuse_share = np.where(total > 0, p_d / np.where(total > 0, total, 1), 1.0)
        write_slot(rows, self.slots()["diffuse_share"], diffuse_share)
        # the share as stored, so that the two sum to 1 in float32
        write_slot(rows, self.slots()["glossy_share"], 1.0 - read_slot(rows, self.slots()["diffuse_share"]))

    def continuation(self, values):
        p_d, p_s = self.lobe_albedos(values)
        return np.minimum(p_d + p_s, 1.0)
