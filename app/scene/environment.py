"""The environment: a constant colour or an HDR latitude-longitude map, with an intensity and a
rotation about the up axis (kernels/environment.cl gives the mapping)."""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])   # Rec. 709 weights of linear R, G, B


@dataclass
class Environment:
    image: np.ndarray          # (H, W, 3) float32 linear RGB radiance
    intensity: float = 1.0
    rotation: float = 0.0      # degrees about +y
    source: str = "constant"   # a file path, or "constant"
    resampled: bool = False    # the image is not the file's (a pbrt equal-area map made lat-long)

    def __repr__(self) -> str:
        from pathtrace.scene.named import vector
        h, w, _ = self.image.shape
        what = f"constant {vector(self.image[0, 0])}" if (h, w) == (1, 1) else f"{self.source} ({w}x{h})"
        return f"<Environment {what}, intensity {self.intensity:g}, rotation {self.rotation:g}>"

    @classmethod
    def constant(cls, color, intensity=1.0):
        image = np.asarray(color, np.float32).reshape(1, 1, 3)
        return cls(image=image, intensity=intensity, source="constant")

    @classmethod
    def from_file(cls, path: Path, intensity=1.0, rotation=0.0, where="environment.map"):
        from pathtrace.io.images import read_hdr
        return cls(read_hdr(path, where), intensity, rotation, str(path))

    def sampling_cdfs(self):
        """The piecewise-constant distribution kernels/environment.cl samples: luminance times
        sin(theta) per texel; a marginal CDF over rows (H + 1 values) and a conditional CDF per
        row (H x (W + 1)). A constant environment needs none (it is sampled by cosine)."""
        h, w, _ = self.image.shape
        if h == 1 and w == 1:
            return np.zeros(2, np.float32), np.zeros(2, np.float32)
        theta = (np.arange(h) + 0.5) / h * np.pi
        weight = (self.image @ LUMINANCE) * np.sin(theta)[:, None]
        weight = np.maximum(weight, 0.0) + 1e-12     # no zero rows
        row_sum = weight.sum(axis=1)
        conditional = np.zeros((h, w + 1))
        conditional[:, 1:] = np.cumsum(weight, axis=1) / row_sum[:, None]
        conditional[:, -1] = 1.0
        marginal = np.zeros(h + 1)
        marginal[1:] = np.cumsum(row_sum) / row_sum.sum()
        marginal[-1] = 1.0
        return marginal.astype(np.float32), conditional.astype(np.float32)

    def rgba(self) -> np.ndarray:
        """The map as float4 texels, the layout the kernel reads."""
        h, w, _ = self.image.shape
        out = np.zeros((h, w, 4), np.float32)
        out[..., :3] = self.image
        return out
