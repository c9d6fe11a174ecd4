"""NumPy mirrors of the structs in kernels/types.h, field for field (tests/test_types.py checks
them against the device's own sizeof and offsetof)."""

import numpy as np

SPHERE = np.dtype((np.float32, 4))  # centre xyz, radius w

MATERIAL = np.dtype([
    ("diffuse", np.float32, 4),   # rho_d rgb, w: P_d
    ("specular", np.float32, 4),  # rho_s rgb, w: exponent n
    ("emission", np.float32, 4),  # Le rgb, w: P_s
])

BVH_CHILD = np.dtype([
    ("lo", np.float32, 3),
    ("index", np.int32),
    ("hi", np.float32, 3),
    ("count", np.int32),
])

BVH_NODE = np.dtype([("child", BVH_CHILD, 2)])

RENDER_PARAMS = np.dtype([
    ("eye", np.float32, 4),
    ("forward", np.float32, 4),
    ("right", np.float32, 4),
    ("up", np.float32, 4),
    ("env_scale", np.float32, 4),
    ("width", np.int32),
    ("height", np.int32),
    ("sample_start", np.uint32),
    ("sample_count", np.uint32),
    ("seed", np.uint32),
    ("max_depth", np.int32),
    ("russian_roulette", np.int32),
    ("env_width", np.int32),
    ("env_height", np.int32),
    ("env_rotation", np.float32),
    ("num_lights", np.int32),
    ("env_pick", np.float32),
    ("pad0", np.int32),
    ("pad1", np.int32),
    ("pad2", np.int32),
    ("pad3", np.int32),
])

LIGHT = np.dtype([
    ("sphere", np.int32),
    ("alias", np.int32),
    ("keep", np.float32),
    ("pick", np.float32),
])


def lobe_probabilities(rho_d, rho_s):
    """P_d and P_s of the lobe choice in kernels/phong.cl: the largest channel of each albedo,
    so that no channel's path weight exceeds 1, scaled down where they sum past 1."""
    p_d = np.max(rho_d, axis=-1)
    p_s = np.max(rho_s, axis=-1)
    total = np.maximum(p_d + p_s, 1.0)
    return p_d / total, p_s / total


def pack_materials(rho_d, rho_s, exponent, emission):
    """Arrays of shape (N, 3), (N, 3), (N,), (N, 3) into a MATERIAL array."""
    rho_d = np.asarray(rho_d, np.float32).reshape(-1, 3)
    rho_s = np.asarray(rho_s, np.float32).reshape(-1, 3)
    out = np.zeros(len(rho_d), MATERIAL)
    p_d, p_s = lobe_probabilities(rho_d, rho_s)
    out["diffuse"][:, :3] = rho_d
    out["diffuse"][:, 3] = p_d
    out["specular"][:, :3] = rho_s
    out["specular"][:, 3] = exponent
    out["emission"][:, :3] = np.asarray(emission, np.float32).reshape(-1, 3)
    out["emission"][:, 3] = p_s
    return out
