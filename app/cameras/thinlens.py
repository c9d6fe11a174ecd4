"""The thin-lens perspective camera (kernels/cameras/thinlens.cl): Mitsuba 3's `thinlens`,
pbrt-v4's `perspective` with a `lensradius` (perspective.py reads pbrt's). With aperture 0 it
is a pinhole, and compiles as one (kernels/cameras/perspective.cl), so that pinholes carry none
of the lens's registers (docs/performance.md). A TOML `perspective` camera that gives its fields
is one."""

from dataclasses import dataclass
from typing import ClassVar

from pathtrace.cameras.camera import Parameter
from pathtrace.cameras.perspective import PerspectiveCamera, mitsuba_vfov

APERTURE = Parameter("aperture", "aperture_radius", mitsuba="aperture_radius", pbrt="lensradius",
                     closed=True, unit="scene units", doc="the lens's radius (0: a pinhole)",
                     viewer=(0.0, 10.0, True))
FOCUS = Parameter("focus_distance", "focus_distance", mitsuba="focus_distance", pbrt="focaldistance",
                  unit="scene units", doc="the distance along the view direction to the plane in focus "
                  "(Mitsuba's default 10,000, pbrt's 10^6)", viewer=(1e-3, 1e4, True))


@dataclass(repr=False)
class ThinLensCamera(PerspectiveCamera):
    aperture: float = 0.0
    focus_distance: float = 1.0

    type: ClassVar[str] = "thinlens"
    parameters: ClassVar[tuple] = (*PerspectiveCamera.parameters, APERTURE, FOCUS)
    kernels: ClassVar[tuple] = ("thinlens",)
    importance: ClassVar[bool] = True
    mitsuba: ClassVar[str] = "thinlens"
    pbrt: ClassVar[str] = "perspective"         # with a lensradius (PerspectiveCamera.from_pbrt)
    toml_aliases: ClassVar[tuple] = ("perspective",)

    @property
    def kernel(self) -> str:
        return "thinlens" if self.aperture > 0 else "perspective"

    def lens(self) -> tuple:
        return (self.aperture, self.focus_distance, 0.0, 0.0)

    @classmethod
    def from_mitsuba(cls, sensor, **frame):
        if not sensor.has("aperture_radius"):
            sensor.fail(None, "a thinlens camera needs an aperture_radius")
        return cls(**frame, vfov=mitsuba_vfov(sensor), aperture=sensor.get("aperture_radius"),
                   focus_distance=sensor.get("focus_distance", 10000.0))       # Mitsuba's default
