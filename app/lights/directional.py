"""A directional light, the sun of a scene (Mitsuba 3's `directional`, pbrt-v4's `distant`):
irradiance `irradiance` (W/m^2, rgb, on a surface facing it) arriving from infinitely far away,
travelling along `direction`. kernels/lights/directional.cl samples it."""

import math
from dataclasses import dataclass

import numpy as np

from pathtrace.lights.light import PBRT_SCALE, DeltaLight, check_color, check_direction, luminance
from pathtrace.parameters import FRAME, Parameter
from pathtrace.device.slots import Slot


def _pbrt_irradiance(value, given):
    """pbrt-v4's DistantLight::Create: L times scale, and times `illuminance` where that is given."""
    value = np.asarray(value, np.float64) * given["scale"]
    return value * given["illuminance"] if given["illuminance"] > 0 else value


@dataclass
class DirectionalLight(DeltaLight):
    direction: np.ndarray
    irradiance: np.ndarray
    name = "directional"
    formats = {"mitsuba": "directional", "pbrt": "distant"}
    parameters = (
        Parameter(None, "point", pbrt="from", pbrt_default=(0.0, 0.0, 0.0), doc="with `to`, the direction"),
        Parameter("direction", "vector", doc="the way the light travels", mitsuba="direction",
                  mitsuba_default=FRAME, pbrt="to", pbrt_default=(0.0, 0.0, 1.0),
                  from_pbrt=lambda to, given: np.asarray(to) - given["from"]),
        Parameter("irradiance", "color", doc="irradiance on a surface facing it, W/m^2", spectrum="illuminant",
                  mitsuba="irradiance", mitsuba_default=1.0, pbrt="L", pbrt_default=1.0, from_pbrt=_pbrt_irradiance),
        PBRT_SCALE,
        Parameter(None, "number", pbrt="illuminance", pbrt_default=-1.0,
                  doc="the illuminance (lux) the light is scaled to, where positive"))
    slots = (Slot("direction", "p0.xyz", "the unit direction the light travels"),
             Slot("irradiance", "p1.xyz", "irradiance E, W/m^2, on a surface facing it"))
    examples = ({"direction": [1.0, -2.0, 0.5], "irradiance": [3.0, 2.5, 1.0]},)

    def check(self):
        self.direction = check_direction("direction", self.direction)
        self.irradiance = check_color("irradiance", self.irradiance)

    def power(self, radius: float) -> float:
        """What falls on the scene: its irradiance over the disk of the scene's bounding sphere,
        as Mitsuba and pbrt-v4 take it."""
        return math.pi * radius * radius * luminance(self.irradiance)
