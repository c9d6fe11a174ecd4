"""The clamp texture: a texture's values clamped into [low, high], as pbrt-v4's materials clamp a
reflectance where they evaluate it (src/pbrt/materials.h: DiffuseMaterial::GetBxDF's
Clamp(texEval(reflectance, ...), 0, 1); CoatedDiffuse's reflectance and albedo): after the
texture's own filtering, not texel by texel. The pbrt reader wraps such a texture in one where
its values may leave [0, 1] (app/materials/bsdf.py: pbrt_clamped); a scene whose textures stay
within compiles none of it."""

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.textures.texture import Texture, TextureType, input_bounds, input_mean


class Clamp(TextureType):
    name = "clamp"
    doc = "tex clamped into [low, high] (as pbrt-v4's materials clamp a reflectance)"
    parameters = (Parameter("tex", "color", 1.0, texture=True, doc="the texture clamped"),
                  Parameter("low", "color", 0.0, texture=True, doc="the lowest value"),
                  Parameter("high", "color", 1.0, texture=True, doc="the highest value"))
    # exact: in each channel the input lies wholly inside, above or below the bounds
    examples = ({"tex": Texture("checkerboard", {"color0": [1.5, 0.2, -0.5], "color1": [2.0, 0.4, -0.2]})},
                {"tex": Texture("checkerboard", {"color0": 0.3, "color1": 0.7}), "low": 0.1, "high": [0.2, 0.8, 1.0]})

    def mean(self, texture):
        # exact where, in each channel, the input's values lie on one side of each bound;
        # otherwise an estimate
        p = texture.params
        return np.clip(input_mean(p["tex"]), input_mean(p["low"]), input_mean(p["high"]))

    def bounds(self, texture):
        p = texture.params
        (lo, hi), (low, _), (_, high) = input_bounds(p["tex"]), input_bounds(p["low"]), input_bounds(p["high"])
        return np.clip(lo, low, high), np.clip(hi, low, high)
