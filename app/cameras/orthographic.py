"""The orthographic camera (kernels/cameras/orthographic.cl; Mitsuba 3's and pbrt-v4's
`orthographic`): parallel rays along the view direction from the points of a rectangle `height`
high, as wide as the image's aspect makes it."""

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pathtrace.cameras.camera import FILM, MAX_EXTENT, PBRT_LENS, PBRT_SCREEN, TO_WORLD, Camera, check_range, \
    pbrt_screen_half_height
from pathtrace.parameters import Parameter

HEIGHT = Parameter("height", "number", 2.0, doc="the view's height, scene units (Mitsuba's and pbrt's come from "
                   "the transform's scale and the screen window)")


@dataclass(repr=False)
class OrthographicCamera(Camera):
    height: float = HEIGHT.default

    type: ClassVar[str] = "orthographic"
    parameters: ClassVar[tuple] = (HEIGHT,)
    format_only: ClassVar[tuple] = (*PBRT_SCREEN, *PBRT_LENS)
    sliders: ClassVar[dict] = {"height": (1e-3, 1e4, True)}
    kernels: ClassVar[tuple] = ("orthographic",)
    mitsuba: ClassVar[str] = "orthographic"
    pbrt: ClassVar[str] = "orthographic"

    def check(self):
        check_range("height", self.height, 0.0, MAX_EXTENT, open_low=True)
        return super().check()

    def half_height(self) -> float:
        return self.height / 2

    def ray(self, aspect: float, x: float, y: float):
        forward, right, up = self.basis(aspect)
        return self.eye + x * right + y * up, forward

    @classmethod
    def from_file(cls, fmt, values, given, frame, warn):
        scale_x, scale_y = (float(np.linalg.norm(given[TO_WORLD][:3, i])) for i in (0, 1))
        if fmt == "mitsuba":
            # Mitsuba's orthographic view spans [-1, 1] across the film's width in camera space,
            # scaled by to_world
            if not math.isclose(scale_x, scale_y, rel_tol=1e-4):
                warn("to_world scales x and y differently; pathtrace keeps the view's width")
            width, height = given[FILM]
            values["height"] = 2 * scale_x * height / width
        else:
            # the screen window spans one world unit per unit, scaled by the transform
            if given["lensradius"] > 0:
                warn("pathtrace's orthographic camera has no lens; 'lensradius' is ignored")
            values["height"] = 2.0 * scale_y * pbrt_screen_half_height(given, warn)
        return super().from_file(fmt, values, given, frame, warn)
