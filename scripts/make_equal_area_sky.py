"""Writes tests/scenes/textures/sky-equal-area.pfm and sky-latlong.pfm: one smooth sky (a
gradient and a broad warm glow) in pbrt-v4's equal-area octahedral layout and in Mitsuba 3's
lat-long layout, each texel the sky's value at the direction its centre stands for, found here
independently of pathtrace (pbrt-v4's EqualAreaSquareToSphere; Mitsuba's envmap mapping, inverted).
equal-area.pbrt lights its scene with the first, equal-area.xml with the second.

    python scripts/make_equal_area_sky.py
"""

from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent.parent / "tests" / "scenes" / "textures"
GLOW = np.array([0.6, 0.5, 0.62]) / np.linalg.norm([0.6, 0.5, 0.62])


def sky(d):
    """Radiance towards unit directions d (..., 3): a blue-white gradient in y and a glow."""
    up = 0.5 + 0.5 * d[..., 1:2]
    glow = np.exp(4.0 * (d @ GLOW - 1.0))[..., None]
    return 0.15 + up * np.array([0.25, 0.35, 0.6]) + glow * np.array([2.5, 1.8, 0.9])


def square_to_sphere(u, v):
    """pbrt-v4's EqualAreaSquareToSphere of points of the unit square."""
    u, v = 2 * u - 1, 2 * v - 1
    up, vp = np.abs(u), np.abs(v)
    signed = 1 - (up + vp)
    r = 1 - np.abs(signed)
    with np.errstate(invalid="ignore", divide="ignore"):
        phi = np.where(r == 0, 1.0, (vp - up) / np.where(r == 0, 1.0, r) + 1) * np.pi / 4
    z = np.copysign(1 - r * r, signed)
    s = r * np.sqrt(np.maximum(0.0, 2 - r * r))
    return np.stack([np.copysign(np.cos(phi), u) * s, np.copysign(np.sin(phi), v) * s, z], axis=-1)


def latlong_to_sphere(u, v):
    """The inverse of Mitsuba 3's envmap lookup, u = atan2(x, -z) / 2 pi (mod 1), v = acos(y) / pi."""
    phi, theta = 2 * np.pi * u, np.pi * v
    return np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=-1)


def write_pfm(path, rgb):
    """A colour PFM: rows stored bottom first, little-endian floats; rgb's row 0 is the top."""
    h, w, _ = rgb.shape
    with open(path, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode("ascii"))
        f.write(np.ascontiguousarray(rgb[::-1], "<f4").tobytes())


def centres(w, h):
    return np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h)


if __name__ == "__main__":
    u, v = centres(64, 64)           # pbrt: image row 0 at v = 0
    write_pfm(OUT / "sky-equal-area.pfm", sky(square_to_sphere(u, v)))
    u, v = centres(128, 64)
    write_pfm(OUT / "sky-latlong.pfm", sky(latlong_to_sphere(u, v)))
