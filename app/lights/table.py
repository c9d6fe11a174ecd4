"""What next-event estimation samples: every light in one table (emissive spheres and
triangles, the environment and the delta lights), chosen in proportion to power through an
alias table."""

from dataclasses import dataclass

import numpy as np

from pathtrace.scene.environment import LUMINANCE
from pathtrace.lights.registry import TAGS
from pathtrace.lights.tree import build_light_tree, light_bounds
from pathtrace.device.types import LIGHT, LIGHT_NODE


# Lights with a place from which "auto" chooses by the light tree: its walk costs more than it
# saves below (PoCL, depth 8, per-pixel variance times time: 0.8x on 242 and 1,862 spheres, 3.7x
# on 20,000 lamps; docs/performance.md)
TREE_MIN = 4096


@dataclass
class LightTable:
    lights: np.ndarray        # LIGHT entries (at least one, a dummy when there are no lights): the
                              # `count` that the alias table chooses among, then, with a light
                              # tree, the tree's lights in the order of its leaves
    count: int                # entries the alias table chooses among
    prim_light: np.ndarray    # (primitives,) int32: per primitive, its entry, or -1
    env_pick: float           # probability of choosing the environment
    types: tuple = ()         # the delta light types in the table (app/lights/registry.py)
    nodes: np.ndarray = None  # the light tree's LIGHT_NODEs (a dummy one without a tree)
    tree: bool = False        # whether lights with a place are chosen through the tree

    @property
    def pick(self) -> np.ndarray:
        """Per primitive, float32: the probability that the alias table chooses it (0 for none;
        with a tree, the tree's probability as a whole), which MIS reads where a path hits it."""
        return np.where(self.prim_light >= 0, self.lights["pick"][np.maximum(self.prim_light, 0)],
                        0.0).astype(np.float32)

    @property
    def leaf(self) -> np.ndarray:
        """Per primitive, int32: its leaf of the light tree (-1 for none; one -1 without a tree)."""
        if not self.tree:
            return np.full(1, -1, np.int32)
        return np.where(self.prim_light >= 0, self.lights["alias"][np.maximum(self.prim_light, 0)], -1).astype(np.int32)


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


def emitted_power(spheres, triangles, sphere_luminance, triangle_luminance):
    """Luminance power of each primitive: pi Le times its emitting area (a sphere's whole
    surface 4 pi r^2; a triangle's front, whose area is half its edges' cross product), from
    the luminance each emits (of its rgb radiance, by LUMINANCE)."""
    r = spheres[:, 3].astype(np.float64)
    sphere_power = np.asarray(sphere_luminance, np.float64) * np.pi * 4 * np.pi * r ** 2
    triangle_power = np.array(triangle_luminance, np.float64)
    lit = np.flatnonzero(triangle_power > 0)      # the areas of emitters only: most emit nothing
    t = triangles[lit].astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    triangle_power[lit] *= np.pi * area
    return np.concatenate([sphere_power, triangle_power])


@dataclass(frozen=True)
class LightPlan:
    """What a scene's kernels compile for its lights (Features.lights, Features.light_tree)."""
    types: tuple = ()         # the delta light types that emit (app/lights/registry.py)
    tree: bool = False        # whether lights with a place are chosen through the light tree


def light_plan(power: np.ndarray, delta_lights=(), radius: float = 1.0, sampler: str = "power") -> LightPlan:
    """The plan of build_light_table's table for the same arguments, `power` in any primitive
    order: known before the BVH orders the primitives, so that a scene's program can build
    beside its tree (app/compiler/compiled.py)."""
    delta = [light for light in delta_lights if light.power(radius) > 0]
    return _plan(np.count_nonzero(power > 0) + sum(light.tree_bounds() is not None for light in delta),
                 [light.name for light in delta], sampler)


def _plan(bounded: int, delta_names: list, sampler: str) -> LightPlan:
    """The plan of `bounded` lights with a place (emitters, points, spots) and delta lights of
    these types, chosen by `sampler`."""
    return LightPlan(tuple(dict.fromkeys(delta_names)),
                     bounded > 0 and (sampler == "tree" or (sampler == "auto" and bounded >= TREE_MIN)))


def build_light_table(power: np.ndarray, environment, delta_lights=(), radius: float = 1.0,
                      prim_bounds=None, sampler: str = "power", texture_rows: dict = None) -> LightTable:
    """power: per primitive, in BVH order; delta_lights: the scene's point, spot and directional
    lights (app/lights/light.py), `radius` the scene's bounding sphere's; prim_bounds(prims):
    the light bounds of primitives `prims` (app/lights/tree.py: primitive_bounds), asked for a
    tree only. The environment, when it is not black, is chosen as often as all other lights
    together (half the time), or always when there are none. sampler "power" chooses every
    light in proportion to its power; "tree" chooses the lights that have a place (emitters,
    points, spots) through a light tree; "auto" the tree from TREE_MIN such lights on.
    texture_rows: {id(texture): its row of the texture table} of the textures lights read.

    The entries: with a tree, its root, the lights at infinity and the environment (which the
    alias table chooses among), then the tree's lights in the order of its leaves; without,
    the emitters, the points and spots, the lights at infinity and the environment."""
    emitters = np.flatnonzero(power > 0)
    delta = [(light, light.power(radius)) for light in delta_lights]
    delta = [(light, w) for light, w in delta if w > 0]
    placed = [(light, w) for light, w in delta if light.tree_bounds() is not None]
    at_infinity = [(light, w) for light, w in delta if light.tree_bounds() is None]
    env_lit = bool(np.any(environment.image > 0)) and environment.intensity > 0
    bounded = len(emitters) + len(placed)
    plan = _plan(bounded, [light.name for light, _ in delta], sampler)
    tree = plan.tree
    bounded_power = np.concatenate([power[emitters], [w for _, w in placed]])
    weights = np.concatenate([[bounded_power.sum()] if tree else bounded_power, [w for _, w in at_infinity]])
    if env_lit:
        weights = np.append(weights, weights.sum() if len(weights) else 1.0)
    nodes = np.zeros(1, LIGHT_NODE)
    if not len(weights):
        return LightTable(np.zeros(1, LIGHT), 0, np.full(len(power), -1, np.int32), 0.0, (), nodes)
    count = len(weights)
    table = np.zeros(count + (bounded if tree else 0), LIGHT)
    table["prim"] = -1
    # where the emitters and the points and spots go: after the top entries, in leaf order, or first
    if tree:
        nodes, leaf = build_light_tree(tree_bounds(emitters, [light for light, _ in placed], bounded_power,
                                                   prim_bounds))
        slot = np.empty(bounded, np.int64)
        slot[np.argsort(leaf)] = count + np.arange(bounded)
        table["type"][0] = len(TAGS)                   # LIGHT_TREE_ROOT (kernels/light_tree.cl)
        table["alias"][slot] = leaf
        nodes["light"][leaf] = slot
        rest = 1
    else:
        slot = np.arange(bounded)
        rest = bounded
    table["type"][slot[:len(emitters)]] = TAGS["area"]
    table["prim"][slot[:len(emitters)]] = emitters
    for k, (light, _) in [*zip(slot[len(emitters):], placed), *enumerate(at_infinity, rest)]:
        table["type"][k] = TAGS[light.name]
        light.pack(table[k], texture_rows or {})
    if env_lit:
        table["type"][count - 1] = TAGS["environment"]
    keep, alias = alias_table(weights)
    table["alias"][:count] = alias
    table["keep"][:count] = keep_threshold(keep)
    table["pick"][:count] = weights / weights.sum()
    if tree:
        table["pick"][count:] = table["pick"][0]
    prim_light = np.full(len(power), -1, np.int32)
    prim_light[emitters] = slot[:len(emitters)]
    return LightTable(table, count, prim_light, float(table["pick"][count - 1]) if env_lit else 0.0, plan.types,
                      nodes, tree)


def tree_bounds(emitters: np.ndarray, placed: list, power: np.ndarray, prim_bounds) -> dict:
    """The light tree's leaves: the emissive primitives `emitters`, then the points and spots
    `placed`, of power `power`."""
    deltas = [light.tree_bounds() for light in placed]
    position = np.array([b[0] for b in deltas], np.float64).reshape(-1, 3)
    of_prims = prim_bounds(emitters)
    return light_bounds(
        np.concatenate([of_prims["lo"], position]), np.concatenate([of_prims["hi"], position]),
        power, np.concatenate([of_prims["axis"], np.array([b[1] for b in deltas]).reshape(-1, 3)]),
        np.concatenate([of_prims["cos_o"], [b[2] for b in deltas]]),
        np.concatenate([of_prims["cos_e"], [b[3] for b in deltas]]))
