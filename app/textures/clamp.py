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
                  Parameter("low", "color", 0.0, doc="the lowest value"),
                  Parameter("high", "color", 1.0, doc="the highest value, not below low"))
    # exact: in each channel the input lies wholly inside, above or below the bounds
    examples = ({"tex": Texture("checkerboard", {"color0": [1.5, 0.2, -0.5], "color1": [2.0, 0.4, -0.2]})},
                {"tex": Texture("checkerboard", {"color0": 0.3, "color1": 0.7}), "low": 0.1, "high": [0.2, 0.8, 1.0]})

    def complete(self, params):
        # constant bounds, in the order the kernel's clamp() needs (OpenCL leaves it undefined
        # where low > high), which make the bounds below exact
        values = super().complete(params)
        for name in ("low", "high"):
            try:
                v = np.asarray(values[name], np.float64)
            except (TypeError, ValueError):       # a texture, a string
                v = np.zeros(0)
            if v.size not in (1, 3) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be a number or three numbers")
            values[name] = np.broadcast_to(v.reshape(-1), 3).copy()
        if np.any(values["low"] > values["high"]):
            raise ValueError(f"low must not exceed high, got {values['low'].tolist()} and {values['high'].tolist()}")
        return values

    def pack(self, texture, row, texels):
        # beside the input's slot 0, the slots no input takes (kernels/textures/clamp.cl)
        row["value"][1, :3] = texture.params["low"]
        row["value"][2, :3] = texture.params["high"]

    def mean(self, texture):
        # exact where, in each channel, the input's values lie on one side of each bound;
        # otherwise an estimate
        p = texture.params
        return np.clip(input_mean(p["tex"]), p["low"], p["high"])

    def bounds(self, texture):
        p = texture.params
        lo, hi = input_bounds(p["tex"])
        return np.clip(lo, p["low"], p["high"]), np.clip(hi, p["low"], p["high"])
