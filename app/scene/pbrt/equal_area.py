"""pbrt-v4's environment maps: a square image in Clarberg's equal-area octahedral layout
("Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD", 2008; pbrt-v4's
EqualAreaSphereToSquare), +z at the centre, -z at the corners. pathtrace's environment is a
lat-long map (kernels/environment.cl: u = 1/2 + atan2(x, -z) / 2 pi, v = acos(y) / pi), so the
reader resamples the square into a finer one, through the light's transform, with pbrt's
nearest-texel lookups."""

import numpy as np

# the lat-long map's rows per row of the square, and the most rows it takes that way
LATLONG_FACTOR = 8
LATLONG_MAX = 2048


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


def square_to_sphere(uv: np.ndarray) -> np.ndarray:
    """Points of the unit square (N, 2) to unit directions (N, 3): sphere_to_square's inverse
    (pbrt-v4's EqualAreaSquareToSphere)."""
    u, v = 2 * uv[:, 0] - 1, 2 * uv[:, 1] - 1
    up, vp = np.abs(u), np.abs(v)
    signed = 1 - (up + vp)
    r = 1 - np.abs(signed)
    with np.errstate(invalid="ignore", divide="ignore"):
        phi = np.where(r == 0, 1.0, (vp - up) / np.where(r == 0, 1.0, r) + 1) * np.pi / 4
    z = np.copysign(1 - r * r, signed)
    s = r * np.sqrt(np.maximum(0.0, 2 - r * r))
    return np.stack([np.copysign(np.cos(phi), u) * s, np.copysign(np.sin(phi), v) * s, z], axis=-1)


def upper_illuminance(square: np.ndarray) -> float:
    """The illuminance by which pbrt-v4 normalises an equal-area map given "illuminance" (Light::
    Create, src/pbrt/lights.cpp): the sum over texels whose centre's direction has z > 0 (light
    space) of luminance times cos theta, times 2 pi / N^2, as pbrt writes it."""
    n = square.shape[0]
    c = (np.arange(n) + 0.5) / n
    uv = np.stack(np.meshgrid(c, c), axis=-1).reshape(-1, 2)       # x along a row, rows down
    z = square_to_sphere(uv)[:, 2]
    lum = square[..., :3].reshape(-1, 3) @ np.array([0.2126, 0.7152, 0.0722])
    return float(np.sum(np.where(z > 0, lum * z, 0.0)) * 2 * np.pi / (n * n))


def latlong_rows(width: int, height: int, first: int, end: int) -> np.ndarray:
    """The direction at each pixel centre of rows first..end of a pathtrace lat-long map of
    width x height: (end - first, width, 3)."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(first, end) + 0.5) / height
    phi = (u - 0.5) * 2 * np.pi
    theta = v * np.pi
    st = np.sin(theta)[:, None]
    return np.stack([st * np.sin(phi)[None, :], np.repeat(np.cos(theta)[:, None], width, 1),
                     -st * np.cos(phi)[None, :]], axis=-1)


def to_latlong(square: np.ndarray, light_from_world: np.ndarray) -> np.ndarray:
    """An equal-area square image (N, N, C) as a lat-long map (kN, 2kN, C), k = LATLONG_FACTOR
    (fewer where that passes LATLONG_MAX rows, at least 1): each pixel takes the square's texel
    in the direction its centre has in the light's space, the nearest one, as pbrt-v4's
    ImageInfiniteLight::ImageLe looks its image up (LookupNearest, WrapMode::OctahedralSphere;
    every direction falls inside the square, so no texel is clamped or wrapped). The one
    bilinear step left is pathtrace's lookup of the lat-long map (kernels/environment.cl), over
    a pixel k times finer than the square's texels."""
    n = square.shape[0]
    k = max(1, min(LATLONG_FACTOR, LATLONG_MAX // n))
    height, width = k * n, 2 * k * n
    out = np.empty((height, width, square.shape[2]), np.float32)
    rows = max(1, (1 << 22) // width)          # directions in chunks of some 4M
    for top in range(0, height, rows):
        d = latlong_rows(width, height, top, min(height, top + rows)).reshape(-1, 3) @ light_from_world.T
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        texel = np.minimum((sphere_to_square(d) * n).astype(np.int64), n - 1)
        out[top:top + rows] = square[texel[:, 1], texel[:, 0]].reshape(-1, width, square.shape[2])
    return out
