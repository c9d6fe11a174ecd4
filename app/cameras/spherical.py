"""The spherical camera (kernels/cameras/spherical.cl): pbrt-v4's `spherical` (`mapping`
`equalarea`, its default, or `equirectangular`; src/pbrt/cameras.cpp, SphericalCamera), a
360-degree view of every direction around `eye`. The image's (u, v) = (x / width, y / height)
covers the whole sphere whatever its aspect. Equirectangular (2:1 gives square pixels): up along
the top row, the camera's right at the left edge, its view direction a quarter of the way across.
Equal-area (1:1): pbrt-v4's octahedral square, up at the centre, down at the corners, the view
direction at the middle of the bottom edge. Mitsuba 3 has no such sensor."""

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pathtrace.cameras.camera import Camera
from pathtrace.parameters import Parameter

MAPPING = Parameter("mapping", "name", "equalarea", doc="how the image covers the sphere",
                    choices=("equalarea", "equirectangular"), pbrt="mapping")


@dataclass(repr=False)
class SphericalCamera(Camera):
    mapping: str = MAPPING.default

    type: ClassVar[str] = "spherical"
    parameters: ClassVar[tuple] = (MAPPING,)
    kernels: ClassVar[tuple] = ("spherical",)
    pbrt: ClassVar[str] = "spherical"

    def basis(self, aspect: float):
        return self.frame()          # pbrt's camera space: +z forward, +x right, +y up

    def lens(self) -> tuple:
        return (float(MAPPING.choices.index(self.mapping)), 0.0, 0.0, 0.0)

    def ray(self, aspect: float, x: float, y: float):
        u, v = (x + 1) / 2, (1 - y) / 2
        if self.mapping == "equirectangular":
            theta, phi = math.pi * v, 2 * math.pi * u
            d = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
        else:
            # imported here: pathtrace.scene imports the cameras
            from pathtrace.scene.pbrt.equal_area import square_to_sphere
            d = square_to_sphere(np.array([[u, v]]))[0]
        forward, right, up = self.frame()
        return self.eye, d[0] * right + d[1] * forward + d[2] * up
