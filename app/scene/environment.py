"""The environment: a constant colour or an HDR latitude-longitude map, with an intensity and a
rotation about the up axis (kernels/environment.cl gives the mapping), and its parameters in the
three formats: pathtrace's [environment], Mitsuba 3's `constant` and `envmap` emitters,
pbrt-v4's `infinite` light (app/parameters.py; the readers place a map by the element's
to_world or CTM, and pbrt-v4's equal-area square becomes a latitude-longitude map)."""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pathtrace.parameters import Parameter

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])   # Rec. 709 weights of linear R, G, B


@dataclass
class Environment:
    image: np.ndarray          # (H, W, 3) float32 linear RGB radiance
    intensity: float = 1.0
    rotation: float = 0.0      # degrees about +y
    source: str = "constant"   # a file path, or "constant"
    resampled: bool = False    # the image is not the file's (a pbrt equal-area map made lat-long)

    name = "environment"
    formats = {"mitsuba": ("constant", "envmap"), "pbrt": "infinite"}
    doc = ("radiance arriving from infinitely far away: a constant colour, or an HDR map (Mitsuba 3's "
           "constant emitter has radiance, its envmap filename and scale)")
    parameters = (
        Parameter("color", "color", 1.0, spectrum="illuminant", mitsuba="radiance", pbrt="L",
                  doc="its radiance, where it has no map"),
        Parameter("map", "string", optional=True, mitsuba="filename", pbrt="filename",
                  doc="an HDR latitude-longitude map (pbrt-v4's: an equal-area square), relative to the "
                      "scene file (TOML: or a map of assets/envmaps)"),
        Parameter("intensity", "number", 1.0, low=0, mitsuba="scale", pbrt="scale", doc="a factor on it"),
        Parameter("rotation", "number", 0.0, doc="degrees about +y (Mitsuba 3's to_world and pbrt-v4's CTM turn it)"),
        Parameter(None, "number", pbrt="illuminance", pbrt_default=-1.0,
                  doc="where positive, the illuminance it gives an upward surface (pbrt-v4's Light::Create)"))
    mitsuba_plugins = {"constant": ("color",), "envmap": ("map", "intensity")}     # which each emitter has

    def __repr__(self) -> str:
        from pathtrace.scene.named import vector
        h, w, _ = self.image.shape
        what = f"constant {vector(self.image[0, 0])}" if (h, w) == (1, 1) else f"{self.source} ({w}x{h})"
        return f"<Environment {what}, intensity {self.intensity:g}, rotation {self.rotation:g}>"

    @classmethod
    def constant(cls, color, intensity=1.0):
        image = np.broadcast_to(np.asarray(color, np.float32), 3).reshape(1, 1, 3)
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
