"""Mixtures of two materials: Mitsuba 3's `blendbsdf` (weight) and pbrt-v4's `mix` (amount), the
second material taken with probability weight at each hit (kernels/bsdfs/blendbsdf.cl). The two
materials are the Material's components; the table gives each blend rows of its own for them
(MaterialTable.set), whose numbers the blend's row holds."""

import numpy as np

from pathtrace.materials.bsdf import NULL, BSDFType, Param
from pathtrace.slots import Slot, read_slot, write_slot

MAX_BLEND_DEPTH = 8     # blends nested in blends, at most (kernels/bsdfs/blendbsdf.cl)


class BlendBSDF(BSDFType):
    name = "blendbsdf"
    examples = ({"weight": 0.3},)
    params = (Param("weight", "number", default=0.5, high=1.0, slot="p0.x",
                    doc="the share of the second material: 0 is the first alone, 1 the second"),)
    # written by MaterialTable.set, which gives the components rows of their own
    derived = (Slot("first", "p0.y", "the first component's row of the material table", packed=False),
               Slot("second", "p0.z", "the second component's row", packed=False))
    doc = ("two materials mixed, f = (1 - weight) f_1 + weight f_2, by taking the second with "
           "probability weight at each hit (Mitsuba 3's blendbsdf, pbrt-v4's mix); `bsdfs` names "
           "or holds the two")
    resolved_first = True          # the kernels choose a component before any BSDF call
    variant_defines = ("BLEND",)

    def defines(self, rows):
        return ("BLEND",) if len(rows) else ()


def depth(material) -> int:
    """How deep blends nest in a Material: 0 for any other type."""
    if material.type != "blendbsdf":
        return 0
    return 1 + max((depth(c) for c in material.components), default=0)


def transmits(material) -> bool:
    """Whether a Material is seen from both sides (a transmissive one, or a blend of them)."""
    from pathtrace.materials.registry import BSDFS
    if material.type == "blendbsdf":
        return any(transmits(c) for c in material.components)
    return BSDFS[material.type].transmits(material.params)


def check_blend(material) -> str | None:
    """A problem with a blend's components, or None."""
    from pathtrace.materials.registry import BSDFS
    if len(material.components) != 2:
        return f"a blendbsdf mixes two materials, got {len(material.components)}"
    for c in material.components:
        if BSDFS[c.type].flags & NULL:
            return "a blendbsdf cannot mix in a null material (no surface)"
        if c.masked:
            return "the materials a blendbsdf mixes cannot have an opacity: give the blend one"
    if depth(material) > MAX_BLEND_DEPTH:
        return f"blendbsdfs nest deeper than {MAX_BLEND_DEPTH}"
    if len({transmits(c) for c in material.components}) > 1:
        return "a blendbsdf cannot mix a transmissive material with a one-sided one"
    return None


def components_of(rows) -> np.ndarray:
    """The rows of the two components of blend rows (MATERIAL rows, or one), as (n, 2) (or (2,))."""
    slots = BlendBSDF().slots()
    return np.stack([read_slot(rows, slots["first"]), read_slot(rows, slots["second"])], axis=-1).astype(np.int64)


def set_components(rows: np.ndarray, components):
    """Writes the rows of a blend's two components into its MATERIAL rows."""
    slots = BlendBSDF().slots()
    write_slot(rows, slots["first"], components[0])
    write_slot(rows, slots["second"], components[1])


def component_rows(rows: np.ndarray) -> np.ndarray:
    """The rows of the two components of each blend among `rows` (MATERIAL rows)."""
    from pathtrace.materials.registry import TAGS
    return components_of(rows[rows["type"] == TAGS["blendbsdf"]]).ravel()


def reachable(table_rows: np.ndarray, used) -> np.ndarray:
    """The rows `used` (indices of table_rows) and every row their blends choose from."""
    found = np.unique(np.asarray(used, np.int64))
    while True:
        more = np.union1d(found, component_rows(table_rows[found]))
        if len(more) == len(found):
            return found
        found = more
