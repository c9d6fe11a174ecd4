"""Diffuse transmission (pbrt-v4's `diffusetransmission`): Lambertian reflection and
transmission with their own colours; kernels/bsdfs/diffusetransmission.cl."""

import numpy as np

from pathtrace.materials.bsdf import TRANSMISSIVE, BSDFType, Param, pbrt_clamped
from pathtrace.parameters import Parameter
from pathtrace.textures.texture import Texture


def _pbrt_scaled(value, given):
    """pbrt-v4's DiffuseTransmissionMaterial: reflectance and transmittance times `scale`,
    clamped into [0, 1] as it evaluates them (pbrt_clamped)."""
    scale = given["scale"]
    if not isinstance(value, Texture):
        return pbrt_clamped(np.asarray(value, np.float64) * scale)
    if scale == 1.0:
        return pbrt_clamped(value)
    from pathtrace.textures.registry import TEXTURES
    return pbrt_clamped(Texture("scale", TEXTURES["scale"].complete({"tex": value, "scale": scale})))


class DiffuseTransmission(BSDFType):
    name = "diffusetransmission"
    examples = ({"reflectance": [0.6, 0.3, 0.2], "transmittance": [0.3, 0.5, 0.1]},
                {"reflectance": 0.1, "transmittance": 0.8}, {"reflectance": 0.5, "transmittance": 0.0})
    formats = {"pbrt": "diffusetransmission"}
    params = (Param("reflectance", "color", default=0.25, high=1.0, doc="R: the share reflected, f = R / pi",
                    slot="p0.xyz", pbrt="reflectance", pbrt_default=0.25, from_pbrt=_pbrt_scaled),
              Param("transmittance", "color", default=0.25, high=1.0,
                    doc="T: the share transmitted, f = T / pi through the surface", slot="p1.xyz",
                    pbrt="transmittance", pbrt_default=0.25, from_pbrt=_pbrt_scaled))
    format_only = (Parameter(None, "number", pbrt="scale", pbrt_default=1.0,
                             doc="a factor on reflectance and transmittance"),)
    flags = TRANSMISSIVE
    # R + T may exceed 1, as pbrt-v4's DiffuseTransmissionMaterial allows (it clamps each into [0, 1],
    # not their sum): such a surface gives out more light than it receives, and a file pbrt-v4
    # renders is rendered, not refused
    doc = ("Lambertian reflection and transmission, the same from either side (pbrt-v4's "
           "diffusetransmission); reflectance + transmittance may exceed 1, as in pbrt-v4, where the "
           "surface gives out more light than it receives")

    def continuation(self, values):
        return np.minimum(np.max(values["reflectance"] + values["transmittance"], axis=-1), 1.0)
