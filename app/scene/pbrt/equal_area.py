"""pbrt-v4's environment maps: a square image in Clarberg's equal-area octahedral layout
("Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD", 2008; pbrt-v4's
EqualAreaSphereToSquare), +z at the centre, -z at the corners. pathtrace's environment is a
lat-long map (kernels/environment.cl: u = 1/2 + atan2(x, -z) / 2 pi, v = acos(y) / pi), so the
reader resamples the square into it, bilinearly, through the light's transform."""

import numpy as np


def sphere_to_square(d: np.ndarray) -> np.ndarray:
    """Unit directions (N, 3) to points of the unit square (N, 2), where the image's first row
    is at v = 0 (pbrt-v4 looks its images up so)."""
    x, y, z = np.abs(d[:, 0]), np.abs(d[:, 1]), np.abs(d[:, 2])
    r = np.sqrt(np.maximum(0.0, 1.0 - z))
    a, b = np.maximum(x, y), np.minimum(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        b = np.where(a == 0, 0.0, b / np.where(a == 0, 1.0, a))
    phi = np.arctan(b) * 2 / np.pi
    phi = np.where(x < y, 1 - phi, phi)
    v = phi * r
    u = r - v
    south = d[:, 2] < 0
    u, v = np.where(south, 1 - v, u), np.where(south, 1 - u, v)
    u = np.copysign(u, d[:, 0])
    v = np.copysign(v, d[:, 1])
    return np.stack([(u + 1) / 2, (v + 1) / 2], axis=-1)


def latlong_directions(width: int, height: int) -> np.ndarray:
    """The direction at each pixel centre of a pathtrace lat-long map: (height, width, 3)."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    phi = (u - 0.5) * 2 * np.pi
    theta = v * np.pi
    st = np.sin(theta)[:, None]
    return np.stack([st * np.sin(phi)[None, :], np.repeat(np.cos(theta)[:, None], width, 1),
                     -st * np.cos(phi)[None, :]], axis=-1)


def to_latlong(square: np.ndarray, light_from_world: np.ndarray) -> np.ndarray:
    """An equal-area square image (N, N, C) as a lat-long map (N, 2N, C): each pixel looks up the
    square, bilinearly, in the direction its world direction has in the light's space."""
    n = square.shape[0]
    d = latlong_directions(2 * n, n).reshape(-1, 3) @ light_from_world.T
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    st = sphere_to_square(d) * n - 0.5
    i0 = np.floor(st).astype(np.int64)
    f = st - i0
    out = 0.0
    for dx in (0, 1):
        for dy in (0, 1):
            w = (f[:, 0] if dx else 1 - f[:, 0]) * (f[:, 1] if dy else 1 - f[:, 1])
            x = np.clip(i0[:, 0] + dx, 0, n - 1)
            y = np.clip(i0[:, 1] + dy, 0, n - 1)
            out = out + w[:, None] * square[y, x]
    return out.reshape(n, 2 * n, -1).astype(np.float32)
