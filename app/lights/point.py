"""A point light (Mitsuba 3's `point`, pbrt-v4's `point`): radiant intensity `intensity` (W/sr,
rgb) in every direction from `position`. kernels/lights/point.cl samples it."""

import math
from dataclasses import dataclass

import numpy as np

from pathtrace.lights.light import PBRT_POWER, PBRT_SCALE, DeltaLight, check_color, check_point, luminance, pbrt_scaled
from pathtrace.parameters import FRAME, Parameter
from pathtrace.device.slots import Slot


@dataclass
class PointLight(DeltaLight):
    position: np.ndarray
    intensity: np.ndarray
    name = "point"
    formats = {"mitsuba": "point", "pbrt": "point"}
    parameters = (
        Parameter("position", "point", doc="where it is", mitsuba="position", mitsuba_default=FRAME,
                  pbrt="from", pbrt_default=(0.0, 0.0, 0.0)),
        Parameter("intensity", "color", doc="radiant intensity, W/sr", spectrum="illuminant",
                  mitsuba="intensity", mitsuba_default=1.0, pbrt="I", pbrt_default=1.0,
                  from_pbrt=pbrt_scaled(lambda given: 4 * math.pi)),
        PBRT_SCALE, PBRT_POWER)
    slots = (Slot("position", "p0.xyz", "where it is"), Slot("intensity", "p1.xyz", "radiant intensity I, W/sr"))
    examples = ({"position": [0.3, 1.0, -0.2], "intensity": [3.0, 2.0, 1.0]},)

    def check(self):
        self.position = check_point("position", self.position)
        self.intensity = check_color("intensity", self.intensity)

    def power(self, radius: float) -> float:
        return 4 * math.pi * luminance(self.intensity)

    def tree_bounds(self):
        """Every direction: normals spread over the sphere, emission within 90 degrees of each."""
        return self.position, np.array([0.0, 0.0, 1.0]), -1.0, 0.0
