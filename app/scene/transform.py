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
