"""Mixtures of two materials: Mitsuba 3's `blendbsdf` (weight) and pbrt-v4's `mix` (amount), the
second material taken with probability weight at each hit (kernels/bsdfs/blendbsdf.cl). The two
materials are the Material's components; the table gives each blend rows of its own for them
(MaterialTable.set), whose numbers the blend's row holds, and checks them (app/materials/table.py:
check_blend)."""

from pathtrace.materials.bsdf import BSDFType, Param
from pathtrace.device.slots import Slot

MAX_BLEND_DEPTH = 8     # blends nested in blends, at most (kernels/bsdfs/blendbsdf.cl)


class BlendBSDF(BSDFType):
    name = "blendbsdf"
    formats = {"mitsuba": "blendbsdf", "pbrt": "mix"}     # their materials are the readers' to find
    examples = ({"weight": 0.3},)
    params = (Param("weight", "number", default=0.5, high=1.0, slot="p0.x", pbrt="amount",
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

