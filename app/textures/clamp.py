"""The clamp texture: a texture's values clamped into constants [low, high], as pbrt-v4's
materials clamp a reflectance where they evaluate it (src/pbrt/materials.h: DiffuseMaterial::
GetBxDF's Clamp(texEval(reflectance, ...), 0, 1); CoatedDiffuse's reflectance and albedo) and its
image textures an albedo's rgb: after the texture's own filtering, not texel by texel. The pbrt
reader wraps such textures in one where their values may leave [0, 1] (app/materials/bsdf.py:
pbrt_clamped); a scene whose textures stay within compiles none of it."""

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.textures.texture import Texture, TextureType, input_bounds, input_mean


class Clamp(TextureType):
    name = "clamp"
    doc = "tex clamped into [low, high] (as pbrt-v4's materials clamp a reflectance)"
    parameters = (Parameter("tex", "color", 1.0, texture=True, doc="the texture clamped"),
                  Parameter("low", "color", 0.0, texture=True, doc="the lowest value, a constant"),
                  Parameter("high", "color", 1.0, texture=True, doc="the highest value, a constant, not below low"))
    # exact: in each channel the input lies wholly inside, above or below the bounds
    examples = ({"tex": Texture("checkerboard", {"color0": [1.5, 0.2, -0.5], "color1": [2.0, 0.4, -0.2]})},
                {"tex": Texture("checkerboard", {"color0": 0.3, "color1": 0.7}), "low": 0.1, "high": [0.2, 0.8, 1.0]})

    def complete(self, params):
        # constant bounds, whose order the kernel's clamp() needs (OpenCL leaves it undefined
        # where low > high), and which make the bounds below exact
        values = super().complete(params)
        if isinstance(values["low"], Texture) or isinstance(values["high"], Texture):
            raise ValueError("low and high must be numbers or three numbers, not textures")
        if np.any(values["low"] > values["high"]):
            raise ValueError(f"low must not exceed high, got {values['low'].tolist()} and {values['high'].tolist()}")
        return values

    def mean(self, texture):
        # exact where, in each channel, the input's values lie on one side of each bound;
        # otherwise an estimate
        p = texture.params
        return np.clip(input_mean(p["tex"]), p["low"], p["high"])

    def bounds(self, texture):
        p = texture.params
        lo, hi = input_bounds(p["tex"])
        return np.clip(lo, p["low"], p["high"]), np.clip(hi, p["low"], p["high"])
