"""The thin-lens perspective camera (kernels/cameras/thinlens.cl): Mitsuba 3's `thinlens`,
pbrt-v4's `perspective` with a `lensradius` (perspective.py reads pbrt's). With aperture 0 it
is a pinhole, and compiles as one (kernels/cameras/perspective.cl), so that pinholes carry none
of the lens's registers (docs/performance.md). A TOML `perspective` camera that gives its fields
is one."""

from dataclasses import dataclass
from typing import ClassVar

from pathtrace.cameras.camera import MAX_EXTENT, PBRT_SCREEN, check_range
from pathtrace.cameras.perspective import MITSUBA_FOV, PerspectiveCamera
from pathtrace.parameters import Parameter

APERTURE = Parameter("aperture_radius", "number", 0.0, doc="the lens's radius, scene units (0: a pinhole)",
                     mitsuba="aperture_radius", pbrt="lensradius")
FOCUS = Parameter("focus_distance", "number", doc="the distance along the view direction to the plane in focus, "
                  "scene units", mitsuba="focus_distance", mitsuba_default=10000.0, pbrt="focaldistance",
                  pbrt_default=1e6)


@dataclass(repr=False)
class ThinLensCamera(PerspectiveCamera):
    aperture_radius: float = APERTURE.default
    focus_distance: float = 1.0

    type: ClassVar[str] = "thinlens"
    parameters: ClassVar[tuple] = (*PerspectiveCamera.parameters, APERTURE, FOCUS)
    format_only: ClassVar[tuple] = (*MITSUBA_FOV, *PBRT_SCREEN)     # pbrt's lens: APERTURE's and FOCUS's names
    sliders: ClassVar[dict] = {**PerspectiveCamera.sliders, "aperture_radius": (0.0, 10.0, True),
                               "focus_distance": (1e-3, 1e4, True)}
    kernels: ClassVar[tuple] = ("thinlens",)
    importance: ClassVar[bool] = True
    mitsuba: ClassVar[str] = "thinlens"
    pbrt: ClassVar[str] = "perspective"         # with a lensradius (PerspectiveCamera.from_file)
    toml_aliases: ClassVar[tuple] = ("perspective",)

    @property
    def kernel(self) -> str:
        return "thinlens" if self.aperture_radius > 0 else "perspective"

    def check(self):
        check_range("aperture_radius", self.aperture_radius, 0.0, MAX_EXTENT)
        check_range("focus_distance", self.focus_distance, 0.0, MAX_EXTENT, open_low=True)
        return super().check()

    def lens(self) -> tuple:
        return (self.aperture_radius, self.focus_distance, 0.0, 0.0)

    @classmethod
    def from_file(cls, fmt, values, given, frame, warn):
        if "aperture_radius" not in values:     # Mitsuba 3's thinlens has no default
            raise ValueError("a thinlens camera needs an aperture_radius")
        return super().from_file(fmt, values, given, frame, warn)
