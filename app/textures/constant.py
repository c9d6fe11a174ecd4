"""The constant texture: one colour everywhere."""

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.textures.texture import TextureType


class Constant(TextureType):
    name = "constant"
    doc = "one colour everywhere"
    formats = {"pbrt": "constant"}
    parameters = (Parameter("value", "color", 1.0, doc="the colour", pbrt="value"),)
    examples = ({"value": [0.2, 0.5, 0.9]}, {"value": 3.5})

    def complete(self, params):
        values = super().complete(params)
        v = np.asarray(values["value"], np.float64)
        if v.size not in (1, 3) or not np.all(np.isfinite(v)):
            raise ValueError("value must be a number or three numbers")
        values["value"] = np.broadcast_to(v.reshape(-1), 3).copy()
        return values

    def from_pbrt(self, values, given, warn):
        """pbrt-v4's constant texture is its value (a number for a float texture)."""
        return values.get("value", self.defaults["value"])

    def pack(self, texture, row, texels):
        row["value"][0, :3] = texture.params["value"]

    def mean(self, texture):
        return np.asarray(texture.params["value"], np.float64)

    def bounds(self, texture):
        return self.mean(texture), self.mean(texture)
