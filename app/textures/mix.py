"""The mix texture (pbrt-v4's): a blend of two textures by an amount."""

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.textures.texture import Texture, TextureType, input_bounds, input_mean


class Mix(TextureType):
    name = "mix"
    doc = "(1 - amount) tex1 + amount tex2 (pbrt-v4's mix; amount's first channel)"
    formats = {"pbrt": "mix"}
    parameters = (Parameter("tex1", "color", 0.0, texture=True, doc="where amount is 0", pbrt="tex1"),  # pbrt-v4's defaults
                  Parameter("tex2", "color", 1.0, texture=True, doc="where amount is 1", pbrt="tex2"),
                  Parameter("amount", "color", 0.5, texture=True, doc="the blend, its first channel", pbrt="amount"))
    pbrt_floats = ("amount",)
    examples = ({"tex1": Texture("checkerboard", {}), "tex2": [0.1, 0.9, 0.4], "amount": 0.6},
                {"tex1": 0.2, "tex2": Texture("checkerboard", {"to_uv": np.diag([3.0, 3.0, 1.0])}), "amount": 0.25},
                {"tex1": [0.8, 0.4, 0.1], "tex2": 0.0, "amount": Texture("checkerboard", {"color0": 0.9, "color1": 0.1})})

    def mean(self, texture):
        a = float(input_mean(texture.params["amount"])[0])
        tex1 = input_mean(texture.params["tex1"])
        return tex1 + (input_mean(texture.params["tex2"]) - tex1) * a

    def bounds(self, texture):
        # (1 - a) t1 + a t2 is linear in each of a, t1 and t2, so its extremes are at the corners
        # of their ranges: for amounts in [0, 1] the two textures' bounds, and beyond them an
        # amount outside [0, 1] extrapolates (pbrt-v4's MixTexture does not clamp it)
        ranges = [input_bounds(texture.params[name]) for name in ("tex1", "tex2")]
        amounts = input_bounds(texture.params["amount"])
        # (in the kernel's form, t1 + (t2 - t1) a, whose terms do not cancel where t1 = t2)
        corners = [t1 + (t2 - t1) * a[0] for a in amounts for t1 in ranges[0] for t2 in ranges[1]]
        return np.min(corners, axis=0), np.max(corners, axis=0)
