"""Linear radiance to display sRGB: exposure, a tone curve (by the names of
pathtrace.rendering.choices.TONEMAPS), and the sRGB transfer function.
shaders/display.frag applies the same steps on the GPU; tests/test_tonemap.py checks they agree."""

import numpy as np


def aces_fit(x):
    """Narkowicz's fit of the ACES filmic curve ("ACES Filmic Tone Mapping Curve", 2015)."""
    return np.clip((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)


def linear_to_srgb(x):
    """The sRGB transfer function (IEC 61966-2-1) on [0, 1]."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def tonemap(linear: np.ndarray, exposure: float = 0.0, curve: str = "standard") -> np.ndarray:
    """(H, W, 3) linear radiance -> sRGB-encoded values in [0, 1]. 'standard' clips at 1."""
    x = np.asarray(linear, np.float64) * 2.0 ** exposure
    x = aces_fit(x) if curve == "aces" else x
    return linear_to_srgb(x)


def to_8bit(srgb: np.ndarray) -> np.ndarray:
    return np.clip(np.round(srgb * 255.0), 0, 255).astype(np.uint8)
