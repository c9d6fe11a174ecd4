"""A spot light: radiant intensity `intensity` (W/sr, rgb) from `position` along `direction`,
full inside `beam_width` of the axis and none beyond `cutoff_angle` (degrees, measured from the
axis). Between them it falls off as Mitsuba 3's `spot` does, linearly in the angle ("linear"),
or as pbrt-v4's `spot` does, by a smoothstep in the cosine ("smoothstep": pbrt's coneangle is
cutoff_angle, coneangle - conedeltaangle is beam_width). kernels/lights/spot.cl samples it."""

import math
from dataclasses import dataclass

import numpy as np

from pathtrace.lights.light import (PBRT_POWER, PBRT_SCALE, DeltaLight, check_angle, check_color, check_direction,
                                    check_point, luminance, pbrt_scaled)
from pathtrace.parameters import FRAME, Parameter
from pathtrace.device.slots import Slot, write_slot

FALLOFFS = ("linear", "smoothstep")


SLOP_COS_E = 0.999     # pbrt-v4's SpotLight::Bounds


def _pbrt_k_e(given) -> float:
    """pbrt-v4's SpotLight::Create: the power of a unit intensity, 2 pi (1 - (cos start + cos end) / 2)."""
    cos_end = math.cos(math.radians(given["coneangle"]))
    cos_start = math.cos(math.radians(given["coneangle"] - given["conedeltaangle"]))
    return 2 * math.pi * (1 - 0.5 * (cos_start + cos_end))


@dataclass
class SpotLight(DeltaLight):
    position: np.ndarray
    direction: np.ndarray
    intensity: np.ndarray
    cutoff_angle: float = 20.0
    beam_width: float = None        # None: 3/4 of cutoff_angle, Mitsuba's default
    falloff: str = "linear"
    name = "spot"
    formats = {"mitsuba": "spot", "pbrt": "spot"}
    parameters = (
        Parameter("position", "point", doc="where it is", mitsuba_default=FRAME, pbrt="from",
                  pbrt_default=(0.0, 0.0, 0.0)),
        Parameter("direction", "vector", doc="its axis (or give look_at)", mitsuba_default=FRAME, pbrt="to",
                  pbrt_default=(0.0, 0.0, 1.0), from_pbrt=lambda to, given: np.asarray(to) - given["from"]),
        Parameter("look_at", "point", doc="a point on its axis, instead of direction", optional=True),
        Parameter("intensity", "color", doc="radiant intensity on the axis, W/sr", spectrum="illuminant",
                  mitsuba="intensity", mitsuba_default=1.0, pbrt="I", pbrt_default=1.0,
                  from_pbrt=pbrt_scaled(_pbrt_k_e)),
        Parameter("cutoff_angle", "number", 20.0, doc="degrees from the axis where the light ends",
                  mitsuba="cutoff_angle", pbrt="coneangle", pbrt_default=30.0),
        Parameter("beam_width", "number", doc="degrees from the axis of full intensity; 3/4 of the cutoff "
                  "where left out", optional=True, mitsuba="beam_width", pbrt="conedeltaangle", pbrt_default=5.0,
                  from_pbrt=lambda delta, given: min(max(given["coneangle"] - delta, 0.0), given["coneangle"])),
        Parameter("falloff", "name", "linear", doc="between beam and cutoff: Mitsuba 3's or pbrt-v4's",
                  choices=FALLOFFS, pbrt_default="smoothstep"),
        PBRT_SCALE, PBRT_POWER)
    unsupported = {"mitsuba": {"texture": "pathtrace's spot lights have no texture"}}
    slots = (Slot("position", "p0.xyz", "where it is"), Slot("cos_cutoff", "p0.w", "cos(cutoff_angle)"),
             Slot("intensity", "p1.xyz", "radiant intensity I on the axis"), Slot("cos_beam", "p1.w", "cos(beam_width)"),
             Slot("direction", "p2.xyz", "the unit axis"),
             Slot("falloff_rate", "p2.w", "the falloff: linear, 1 / (cutoff - beam) in radians (0 where there is "
                                     "no band between them), or the smoothstep, -1"))
    examples = ({"position": [0.0, 1.0, 0.0], "look_at": [0.4, 0.0, 0.1], "intensity": 2.0, "cutoff_angle": 40.0,
                 "beam_width": 25.0},
                {"position": [0.2, 1.5, 0.0], "direction": [0.0, -1.0, 0.3], "intensity": [4.0, 3.0, 2.0],
                 "cutoff_angle": 30.0, "beam_width": 30.0, "falloff": "smoothstep"})

    @classmethod
    def resolve(cls, values):
        if "look_at" in values:
            if "direction" in values:
                raise ValueError("give either 'direction' or 'look_at', not both")
            values["direction"] = np.asarray(values.pop("look_at")) - values.get("position", np.zeros(3))
            if not np.any(values["direction"]):      # (named as the file gave it, not as the direction it makes)
                raise ValueError("look_at: must differ from position")
        return values

    def check(self):
        self.position = check_point("position", self.position)
        self.direction = check_direction("direction", self.direction)
        self.intensity = check_color("intensity", self.intensity)
        self.cutoff_angle = check_angle("cutoff_angle", self.cutoff_angle, 180.0)
        if self.beam_width is None:
            self.beam_width = 0.75 * self.cutoff_angle
        if not 0 <= self.beam_width <= self.cutoff_angle:
            raise ValueError(f"beam_width: must be in [0, cutoff_angle = {self.cutoff_angle:g}] degrees, "
                             f"got {self.beam_width:g}")
        if self.falloff not in FALLOFFS:
            raise ValueError(f"falloff: must be linear or smoothstep, got {self.falloff!r}")

    def power(self, radius: float) -> float:
        """Its intensity over the solid angle of the cone halfway between beam and cutoff (the
        exact power for selection matters only for the variance)."""
        cos_mid = math.cos(math.radians(0.5 * (self.cutoff_angle + self.beam_width)))
        return 2 * math.pi * (1 - cos_mid) * luminance(self.intensity)

    def pack(self, row, texture_rows):
        super().pack(row, texture_rows)
        width = math.radians(self.cutoff_angle - self.beam_width)
        for name, value in (("cos_cutoff", math.cos(math.radians(self.cutoff_angle))),
                            ("cos_beam", math.cos(math.radians(self.beam_width))),
                            ("falloff_rate", (1.0 / width if width > 0 else 0.0) if self.falloff == "linear" else -1.0)):
            write_slot(row, self.slot_of(name), value)

    def tree_bounds(self):
        """pbrt-v4's spot bounds: its axis, full out to the beam, then falling off to the cutoff
        (SpotLight::Bounds, lights.cpp). theta_e is kept above pbrt's slop, cos 0.999, which
        pbrt-v4 applies only where the band rounds to nothing: the tree's importance test
        (cos theta' <= cos theta_e, kernels/light_tree.cl) would refuse every point of a
        hard-edged spot (beam = cutoff) that has theta_e 0, pbrt-v4's included. Beyond the cutoff
        the light itself gives nothing, so the slop costs only wasted samples there."""
        return (self.position, self.direction, math.cos(math.radians(self.beam_width)),
                min(math.cos(math.radians(self.cutoff_angle - self.beam_width)), SLOP_COS_E))
