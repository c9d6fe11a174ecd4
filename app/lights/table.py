"""What next-event estimation samples: every light in one table (emissive spheres and
triangles, the environment and the delta lights), chosen in proportion to power through an
alias table."""

from dataclasses import dataclass

import numpy as np

from pathtrace.environment import LUMINANCE
from pathtrace.lights.registry import TAGS
from pathtrace.types import LIGHT


@dataclass
class LightTable:
    lights: np.ndarray        # LIGHT entries (at least one, a dummy when there are no lights)
    count: int                # real entries
    pick: np.ndarray          # (primitives,) float32: per primitive, the probability of choosing it
    env_pick: float           # probability of choosing the environment
    types: tuple = ()         # the names of the light types in the table (app/lights/registry.py)


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


def keep_threshold(keep: np.ndarray) -> np.ndarray:
    """Keep probabilities as the kernel compares them: a uniform 32-bit word below the threshold
    keeps, so the probability is threshold / 2^32, within 2^-32 of `keep` (1 becomes 1 - 2^-32;
    Vose's construction leaves keep 1 only where alias is the entry itself)."""
    return np.minimum(np.round(np.asarray(keep, np.float64) * 2.0**32), 2**32 - 1).astype(np.uint32)


def emitted_power(spheres, triangles, emission_of_sphere, emission_of_triangle):
    """Luminance power of each primitive: pi Le times its emitting area (a sphere's whole
    surface 4 pi r^2; a triangle's front, whose area is half its edges' cross product)."""
    r = spheres[:, 3].astype(np.float64)
    sphere_power = (emission_of_sphere @ LUMINANCE) * np.pi * 4 * np.pi * r ** 2
    t = triangles.astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    triangle_power = (emission_of_triangle @ LUMINANCE) * np.pi * area
    return np.concatenate([sphere_power, triangle_power])


def build_light_table(power: np.ndarray, environment, delta_lights=(), radius: float = 1.0) -> LightTable:
    """power: per primitive, in BVH order; delta_lights: the scene's point, spot and directional
    lights (app/lights/light.py), `radius` the scene's bounding sphere's. The environment, when
    it is not black, is chosen as often as all other lights together (half the time), or always
    when there are none."""
    pick = np.zeros(len(power), np.float32)
    emitters = np.flatnonzero(power > 0)
    delta_lights = [light for light in delta_lights if light.power(radius) > 0]
    env_lit = bool(np.any(environment.image > 0)) and environment.intensity > 0
    weights = np.concatenate([power[emitters], [light.power(radius) for light in delta_lights]])
    count = len(weights)
    if env_lit:
        weights = np.append(weights, weights.sum() if count else 1.0)
    if not len(weights):
        return LightTable(np.zeros(1, LIGHT), 0, pick, 0.0)
    keep, alias = alias_table(weights)
    table = np.zeros(len(weights), LIGHT)
    table["prim"] = -1
    table["prim"][:len(emitters)] = emitters
    table["type"][:len(emitters)] = TAGS["area"]
    for row, light in zip(table[len(emitters):count], delta_lights):
        row["type"] = TAGS[light.name]
        light.pack(row)
    if env_lit:
        table["type"][-1] = TAGS["environment"]
    table["alias"] = alias
    table["keep"] = keep_threshold(keep)
    table["pick"] = weights / weights.sum()
    pick[emitters] = table["pick"][:len(emitters)]
    types = (("area",) if len(emitters) else ()) + (("environment",) if env_lit else ()) \
        + tuple(dict.fromkeys(light.name for light in delta_lights))
    return LightTable(table, len(table), pick, float(table["pick"][-1]) if env_lit else 0.0, types)
