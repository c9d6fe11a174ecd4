"""The pinhole perspective camera (kernels/cameras/perspective.cl): Mitsuba 3's `perspective`,
pbrt-v4's `perspective` without a lens (with one it reads as a thin lens, thinlens.py)."""

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pathtrace.cameras.camera import FILM, MAX_EXTENT, PBRT_LENS, PBRT_SCREEN, Camera, check_choice, check_range, \
    pbrt_screen_half_height
from pathtrace.parameters import Parameter

VFOV = Parameter("vfov", "number", 45.0, doc="the vertical field of view, degrees in (0, 180) (Mitsuba's "
                 "fov along fov_axis, pbrt's on the shorter image axis, converted)", mitsuba="fov", pbrt="fov",
                 pbrt_default=90.0)
# Mitsuba 3's (include/mitsuba/render/sensor.h, parse_fov)
MITSUBA_FOV = (Parameter(None, "name", choices=("x", "y", "diagonal", "smaller", "larger"), mitsuba="fov_axis",
                         mitsuba_default="x", doc="the image axis that fov spans"),
               Parameter(None, "string", mitsuba="focal_length", doc="without a fov: a length in mm on a 36 x 24 mm "
                         "film's diagonal (default 50mm)"))


@dataclass(repr=False)
class PerspectiveCamera(Camera):
    vfov: float = VFOV.default

    type: ClassVar[str] = "perspective"
    parameters: ClassVar[tuple] = (VFOV,)
    format_only: ClassVar[tuple] = (*MITSUBA_FOV, *PBRT_SCREEN, *PBRT_LENS)
    sliders: ClassVar[dict] = {"vfov": (0.1, 179.9, False)}
    kernels: ClassVar[tuple] = ("perspective",)
    importance: ClassVar[bool] = True
    mitsuba: ClassVar[str] = "perspective"
    pbrt: ClassVar[str] = "perspective"

    def half_height(self) -> float:
        return math.tan(math.radians(self.vfov) / 2)

    def check(self):
        # a field of view of 180 degrees or more has no film plane
        check_range("vfov", self.vfov, 0.0, 180.0, open_low=True, open_high=True)
        return super().check()

    def ray(self, aspect: float, x: float, y: float):
        forward, right, up = self.basis(aspect)
        d = forward + x * right + y * up
        return self.eye, d / np.linalg.norm(d)

    @classmethod
    def from_file(cls, fmt, values, given, frame, warn):
        if fmt == "mitsuba":
            values["vfov"] = mitsuba_vfov(values, given, warn)
            return super().from_file(fmt, values, given, frame, warn)
        fov = values["vfov"]
        if not 0 < fov < 180:
            raise ValueError(f"fov: must lie in (0, 180) degrees, got {fov:g}")
        # screen space spans tan(fov / 2) per unit (pbrt-v4's Perspective(fov, n, f)), and the
        # screen window's height frames the image (camera.py: pbrt_screen_half_height)
        half = pbrt_screen_half_height(given, warn)
        values["vfov"] = math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * half))
        lens = given["lensradius"]
        if lens > 0:
            return cls(**frame, **values).as_type("thinlens", aperture_radius=lens,
                                                  focus_distance=given["focaldistance"]).check()
        if lens < 0:
            raise ValueError(f"lensradius: must be in [0, {MAX_EXTENT:g}], got {lens:g}")
        return super().from_file(fmt, values, given, frame, warn)      # focaldistance, without a lens, changes nothing


def mitsuba_vfov(values, given, warn) -> float:
    """The vertical field of view of a Mitsuba perspective or thin-lens sensor's fov and
    fov_axis, or its focal_length (on a 36 x 24 mm film's diagonal, as Mitsuba takes it)."""
    axis, text = given["fov_axis"], given["focal_length"]
    check_choice("fov_axis", axis, MITSUBA_FOV[0].choices)
    if "vfov" in values:
        fov = values["vfov"]
        if text is not None:
            warn("Mitsuba 3 takes a fov or a focal_length, not both; pathtrace uses the fov", "focal_length")
    else:
        text = "50mm" if text is None else text
        try:
            f = float(text.removesuffix("mm"))
        except ValueError:
            raise ValueError(f"focal_length: must be a length in mm, got {text!r}") from None
        if not f > 0:
            raise ValueError(f"focal_length: must be positive, got {text!r}")
        fov, axis = math.degrees(2 * math.atan(math.hypot(36, 24) / (2 * f))), "diagonal"
    if not 0 < fov < 180:
        raise ValueError(f"fov: must lie in (0, 180) degrees, got {fov:g}")
    return vertical_fov(fov, axis, *given[FILM])


def vertical_fov(fov: float, axis: str, w: int, h: int) -> float:
    """The vertical field of view of Mitsuba's `fov` along `fov_axis` on a film w x h."""
    scale = {"x": h / w, "y": 1.0, "diagonal": h / math.hypot(w, h),
             "smaller": h / w if w < h else 1.0, "larger": h / w if w > h else 1.0}[axis]
    return math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * scale))
