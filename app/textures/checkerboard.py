"""The checkerboard texture (Mitsuba 3's): two colours in alternating squares of uv."""

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.textures.texture import Texture, TextureType, input_bounds, input_mean


class Checkerboard(TextureType):
    name = "checkerboard"
    doc = "color0 and color1 in alternating squares of the unit of uv (Mitsuba 3's checkerboard)"
    formats = {"mitsuba": "checkerboard", "pbrt": "checkerboard"}
    parameters = (Parameter("color0", "color", 0.4, texture=True, mitsuba="color0", doc="where u's and v's halves agree",
                            pbrt="tex1", pbrt_default=1.0),      # Mitsuba 3's defaults, and pbrt-v4's
                  Parameter("color1", "color", 0.2, texture=True, mitsuba="color1", doc="elsewhere",
                            pbrt="tex2", pbrt_default=0.0))
    format_only = (Parameter(None, "integer", pbrt="dimension", pbrt_default=2, doc="2 or 3 (pbrt-v4)"),)
    pbrt_uv = 0.5       # pbrt-v4's squares are a unit of (s, t), Mitsuba's half a unit of uv
    examples = ({}, {"color0": [0.9, 0.1, 0.2], "color1": 0.3, "to_uv": np.diag([4.0, 2.0, 1.0])},
                {"color0": Texture("constant", {"value": [0.1, 0.7, 0.3]}), "color1": [1.5, 0.0, 0.25]})

    def from_pbrt(self, values, given, warn):
        if given["dimension"] != 2:
            warn("pathtrace's checkerboard is 2D; the 3D one is taken as 2D")
        return super().from_pbrt(values, given, warn)

    def mean(self, texture):
        return (input_mean(texture.params["color0"]) + input_mean(texture.params["color1"])) / 2

    def bounds(self, texture):
        (lo0, hi0), (lo1, hi1) = input_bounds(texture.params["color0"]), input_bounds(texture.params["color1"])
        return np.minimum(lo0, lo1), np.maximum(hi0, hi1)
