"""A pinhole camera given by eye, look-at point, up vector and vertical field of view."""

from dataclasses import dataclass, field

import numpy as np


def _normalize(v):
    return v / np.linalg.norm(v)


@dataclass
class Camera:
    eye: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 5.0]))
    look_at: np.ndarray = field(default_factory=lambda: np.zeros(3))
    up: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    vfov: float = 45.0

    def __post_init__(self):
        self.eye = np.asarray(self.eye, np.float64)
        self.look_at = np.asarray(self.look_at, np.float64)
        self.up = np.asarray(self.up, np.float64)

    def basis(self, aspect: float):
        """Unit forward, and right and up scaled so that forward + x right + y up, x and y in
        [-1, 1], spans the image (the kernel's camera_direction)."""
        forward = _normalize(self.look_at - self.eye)
        right = _normalize(np.cross(forward, self.up))
        up = np.cross(right, forward)
        half_height = np.tan(np.radians(self.vfov) / 2.0)
        return forward, right * half_height * aspect, up * half_height

    def copy(self) -> "Camera":
        return Camera(self.eye.copy(), self.look_at.copy(), self.up.copy(), self.vfov)
