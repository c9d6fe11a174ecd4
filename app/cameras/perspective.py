"""The pinhole perspective camera (kernels/cameras/perspective.cl): Mitsuba 3's `perspective`,
pbrt-v4's `perspective` without a lens (with one it reads as a thin lens, thinlens.py)."""

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pathtrace.cameras.camera import Camera, check_range, pbrt_screen_half_height
from pathtrace.parameters import Parameter

VFOV = Parameter("vfov", "number", 45.0, doc="the vertical field of view, degrees in (0, 180) (Mitsuba's "
                 "fov along fov_axis, pbrt's on the shorter image axis, converted)", mitsuba="fov", pbrt="fov",
                 pbrt_default=90.0)


@dataclass(repr=False)
class PerspectiveCamera(Camera):
    vfov: float = VFOV.default

    type: ClassVar[str] = "perspective"
    parameters: ClassVar[tuple] = (VFOV,)
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
    def from_mitsuba(cls, sensor, **frame):
        return cls(**frame, vfov=mitsuba_vfov(sensor))

    @classmethod
    def from_pbrt(cls, camera, **frame):
        fov = camera.get("fov", 90.0)
        if not 0 < fov < 180:
            camera.fail("fov", f"must lie in (0, 180) degrees, got {fov:g}")
        # screen space spans tan(fov / 2) per unit (pbrt-v4's Perspective(fov, n, f)), and the
        # screen window's height frames the image (camera.py: pbrt_screen_half_height)
        vfov = math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * pbrt_screen_half_height(camera)))
        lens = camera.get("lensradius", 0.0)
        if lens > 0:
            return cls(**frame, vfov=vfov).as_type("thinlens", aperture_radius=lens,
                                                   focus_distance=camera.get("focaldistance", 1e6))
        if lens < 0:
            camera.fail("lensradius", f"must be in [0, 1e+30], got {lens:g}")
        camera.get("focaldistance", 1e6)      # read: without a lens it changes nothing
        return cls(**frame, vfov=vfov)


def mitsuba_vfov(sensor) -> float:
    """The vertical field of view of a Mitsuba perspective or thin-lens sensor's fov and
    fov_axis, or its focal_length (on a 36 x 24 mm film's diagonal, as Mitsuba takes it)."""
    axis = sensor.get("fov_axis", "x", "string")
    if axis not in ("x", "y", "diagonal", "smaller", "larger"):
        sensor.fail("fov_axis", f"must be x, y, diagonal, smaller or larger, got {axis!r}")
    if sensor.has("fov"):
        fov = sensor.get("fov")
    else:
        text = sensor.get("focal_length", "50mm", "string")
        try:
            f = float(text.removesuffix("mm"))
        except ValueError:
            sensor.fail("focal_length", f"must be a length in mm, got {text!r}")
        if not f > 0:
            sensor.fail("focal_length", f"focal_length must be positive, got {text!r}")
        fov, axis = math.degrees(2 * math.atan(math.hypot(36, 24) / (2 * f))), "diagonal"
    if not 0 < fov < 180:
        sensor.fail("fov", f"the field of view must lie in (0, 180) degrees, got {fov}")
    return vertical_fov(fov, axis, sensor.width, sensor.height)


def vertical_fov(fov: float, axis: str, w: int, h: int) -> float:
    """The vertical field of view of Mitsuba's `fov` along `fov_axis` on a film w x h."""
    scale = {"x": h / w, "y": 1.0, "diagonal": h / math.hypot(w, h),
             "smaller": h / w if w < h else 1.0, "larger": h / w if w > h else 1.0}[axis]
    return math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * scale))
