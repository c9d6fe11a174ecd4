"""The environment: a constant colour or an HDR latitude-longitude map, with an intensity and a
rotation about the up axis (kernels/environment.cl gives the mapping)."""

from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass
class Environment:
    image: np.ndarray          # (H, W, 3) float32 linear RGB radiance
    intensity: float = 1.0
    rotation: float = 0.0      # degrees about +y
    source: str = "constant"   # a file path, or "constant"

    @classmethod
    def constant(cls, color, intensity=1.0):
        image = np.asarray(color, np.float32).reshape(1, 1, 3)
        return cls(image=image, intensity=intensity, source="constant")

    @classmethod
    def from_file(cls, path: Path, intensity=1.0, rotation=0.0, where="environment.map"):
        from app.image_io import read_hdr
        return cls(read_hdr(path, where), intensity, rotation, str(path))

    def rgba(self) -> np.ndarray:
        """The map as float4 texels, the layout the kernel reads."""
        h, w, _ = self.image.shape
        out = np.zeros((h, w, 4), np.float32)
        out[..., :3] = self.image
        return out
