"""What next-event estimation samples: the emissive spheres, chosen in proportion to their
power through an alias table, and the environment, chosen with probability `env_pick`."""

from dataclasses import dataclass

import numpy as np

from app.environment import LUMINANCE
from app.types import LIGHT


@dataclass
class LightTable:
    lights: np.ndarray        # LIGHT entries (at least one, a dummy when there are no lights)
    count: int                # real entries
    pick: np.ndarray          # (N,) float32: per sphere, the probability of choosing it
    env_pick: float           # probability of sampling the environment instead


def alias_table(weights: np.ndarray):
    """Walker's alias method with Vose's construction ("A Linear Algorithm for Generating
    Random Numbers with a Given Distribution", 1991): keep[i] and alias[i] such that choosing
    i uniformly, then keeping it with probability keep[i] or else taking alias[i], selects i
    with probability weights[i] / sum(weights)."""
    n = len(weights)
    scaled = weights / weights.sum() * n
    keep = np.ones(n)
    alias = np.arange(n)
    small = [i for i in range(n) if scaled[i] < 1.0]
    large = [i for i in range(n) if scaled[i] >= 1.0]
    while small and large:
        s, g = small.pop(), large.pop()
        keep[s], alias[s] = scaled[s], g
        scaled[g] -= 1.0 - scaled[s]
        (small if scaled[g] < 1.0 else large).append(g)
    return keep, alias


def build_light_table(spheres: np.ndarray, emission: np.ndarray, environment) -> LightTable:
    """spheres and emission in the BVH's order. A sphere of radiance Le and radius r emits the
    power pi Le 4 pi r^2; lights are chosen in proportion to its luminance."""
    power = (emission @ LUMINANCE) * 4 * np.pi ** 2 * spheres[:, 3].astype(np.float64) ** 2
    emitters = np.flatnonzero(power > 0)
    pick = np.zeros(len(spheres), np.float32)
    env_dark = not np.any(environment.image > 0) or environment.intensity == 0
    if not len(emitters):
        return LightTable(np.zeros(1, LIGHT), 0, pick, 1.0)
    env_pick = 0.0 if env_dark else 0.5
    weights = power[emitters]
    keep, alias = alias_table(weights)
    table = np.zeros(len(emitters), LIGHT)
    table["sphere"] = emitters
    table["alias"] = alias
    table["keep"] = keep
    table["pick"] = weights / weights.sum()
    pick[emitters] = table["pick"]
    return LightTable(table, len(emitters), pick, env_pick)
