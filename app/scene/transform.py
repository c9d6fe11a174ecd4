"""Affine transforms of shapes: 4x4 matrices acting on column vectors, composed as a scene file
states them (scale, then rotate, then translate), and applied to points and normals."""

import numpy as np


def rotation(axis, degrees) -> np.ndarray:
    """The 4x4 rotation by `degrees` about `axis` (Rodrigues' formula), counter-clockwise when
    the axis points at the viewer, as in Mitsuba 3 and pbrt."""
    a = np.asarray(axis, np.float64)
    a = a / np.linalg.norm(a)
    t = np.radians(degrees)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    m = np.eye(4)
    m[:3, :3] = np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * (k @ k)
    return m


def scaling(s) -> np.ndarray:
    return np.diag([*np.broadcast_to(np.asarray(s, np.float64), 3), 1.0])


def translation(t) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = t
    return m


def transform_points(m: np.ndarray, points: np.ndarray) -> np.ndarray:
    p = np.asarray(points, np.float64) @ m[:3, :3].T + m[:3, 3]
    return p


def transform_normals(m: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Normals transform by the inverse transpose; the result is renormalised."""
    n = np.asarray(normals, np.float64) @ np.linalg.inv(m[:3, :3])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.where(length > 0, length, 1.0)


def flips_handedness(m: np.ndarray) -> bool:
    """A mirroring transform turns counter-clockwise corners clockwise."""
    return np.linalg.det(m[:3, :3]) < 0


def look_at(eye, target, up) -> np.ndarray:
    """The camera-to-world transform of a camera at `eye` looking at `target`: its columns x =
    up x forward (normalised), y = forward x x, z = forward and the eye, as Mitsuba 3's lookat
    and pbrt-v4's LookAt (whose CTM is its inverse) build it. Raises ValueError where the view
    direction or the x axis is undefined."""
    eye, target, up = (np.asarray(v, np.float64) for v in (eye, target, up))
    d = target - eye
    if np.linalg.norm(d) == 0:
        raise ValueError("the point looked at must differ from the eye")
    d /= np.linalg.norm(d)
    x = np.cross(up, d)
    if not np.linalg.norm(x) > 1e-9 * np.linalg.norm(up):     # a zero up vector too
        raise ValueError("up must be a vector not parallel to the view direction")
    m = np.eye(4)
    m[:3, 0] = x / np.linalg.norm(x)
    m[:3, 1], m[:3, 2], m[:3, 3] = np.cross(d, m[:3, 0]), d, eye
    return m
