"""A directional light, the sun of a scene (Mitsuba 3's `directional`, pbrt-v4's `distant`):
irradiance `irradiance` (W/m^2, rgb, on a surface facing it) arriving from infinitely far away,
travelling along `direction`. kernels/lights/directional.cl samples it."""

import math
from dataclasses import dataclass

import numpy as np

from pathtrace.lights.light import DeltaLight, check_color, check_direction, luminance


@dataclass
class DirectionalLight(DeltaLight):
    direction: np.ndarray
    irradiance: np.ndarray
    name = "directional"
    fields = ("direction", "irradiance")
    examples = ({"direction": [1.0, -2.0, 0.5], "irradiance": [3.0, 2.5, 1.0]},)

    def check(self):
        self.direction = check_direction("direction", self.direction)
        self.irradiance = check_color("irradiance", self.irradiance)

    def power(self, radius: float) -> float:
        """What falls on the scene: its irradiance over the disk of the scene's bounding sphere,
        as Mitsuba and pbrt-v4 take it."""
        return math.pi * radius * radius * luminance(self.irradiance)
