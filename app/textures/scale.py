"""The scale texture (pbrt-v4's): a texture times a factor."""

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.textures.texture import Texture, TextureType, input_bounds, input_mean


class Scale(TextureType):
    name = "scale"
    doc = "tex times scale (pbrt-v4's scale)"
    formats = {"pbrt": "scale"}
    parameters = (Parameter("tex", "color", 1.0, texture=True, doc="the texture scaled", pbrt="tex"),
                  Parameter("scale", "color", 1.0, texture=True, doc="the factor", pbrt="scale"))
    pbrt_floats = ("scale",)
    examples = ({"tex": [0.5, 0.25, 1.0], "scale": Texture("checkerboard", {"color0": 2.0, "color1": 0.5})},
                {"tex": Texture("checkerboard", {"color0": [0.9, 0.1, 0.2], "color1": 0.3}), "scale": [2.0, 0.5, 1.0]})

    def mean(self, texture):
        # exact where either input is constant; otherwise an estimate that is 0 only where the
        # product is 0 everywhere
        return input_mean(texture.params["tex"]) * input_mean(texture.params["scale"])

    def bounds(self, texture):
        a, b = input_bounds(texture.params["tex"]), input_bounds(texture.params["scale"])
        products = np.array([x * y for x in a for y in b])
        return products.min(axis=0), products.max(axis=0)
