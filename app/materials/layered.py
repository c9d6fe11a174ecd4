"""pbrt-v4's layered materials, evaluated by random walks between the layers
(kernels/layered.cl), with pbrt-v4's parameters and defaults: `coateddiffuse`, a Lambertian base
under a smooth or rough dielectric coating with a layer of medium between them, and
`coatedconductor`, a metal base under the same."""

import math
from dataclasses import replace

import numpy as np

from pathtrace.materials.bsdf import DELTA, BSDFType, Param, pbrt_clamped
from pathtrace.materials.conductor import METAL_PARAMS, RoughConductor, pbrt_metal, pbrt_metal_params, resolve_metal
from pathtrace.materials.dielectric import PBRT_ETA, pbrt_eta
from pathtrace.materials.microfacet import (GGX_PARAMS, PBRT_REMAP, SMOOTH_ALPHA, pbrt_alphas, pbrt_rough,
                                            pbrt_roughness)
from pathtrace.device.slots import Slot, read_slot, write_slot

MAX_WALK_DEPTH = 100      # maxdepth: events per random walk
MAX_WALKS = 16            # nsamples: walks per estimate

_LAYER_PARAMS = (       # pbrt-v4's names and defaults
    Param("thickness", "number", default=0.01, low=1e-6, high=1e3, pbrt="thickness",
          doc="the layer between coating and base, in units of its extinction (1 per unit)"),
    Param("albedo", "color", default=0.0, high=1.0, pbrt="albedo", from_pbrt=pbrt_clamped,
          doc="the layer's single-scattering albedo; 0: it only absorbs"),
    Param("g", "number", default=0.0, low=-0.999, high=0.999, pbrt="g",
          doc="the layer's Henyey-Greenstein phase function's mean cosine"),
    Param("maxdepth", "number", default=10, low=1, high=MAX_WALK_DEPTH, pbrt="maxdepth", pbrt_kind="integer",
          doc="events per random walk"),
    Param("nsamples", "number", default=1, low=1, high=MAX_WALKS, pbrt="nsamples", pbrt_kind="integer",
          doc="random walks per estimate"),
)


PBRT_COATING_ETA = replace(PBRT_ETA, doc="the coating's IOR (a spectrum: its mean; below 1: its inverse)")


def pbrt_coating_eta(given: dict, name: str, warn) -> float:
    """A coating's pbrt-v4 eta, which pathtrace's coatings take above 1: below, its inverse,
    with a warning."""
    eta = pbrt_eta(given, name)
    if eta < 1:
        warn(f"{name} {eta:g} < 1: pathtrace's coatings are denser than the outside; it uses {1 / eta:.4g}")
        eta = 1 / eta
    return eta


def in_slots(params: tuple, **slots) -> tuple:
    """params with the slots `slots` gives by name, constants the kernels read (the random walks
    need them as they are, not a texture's value)."""
    return tuple(replace(p, slot=slots[p.name], constant=True) if p.name in slots else p for p in params)


_ALPHA = replace(GGX_PARAMS[0], default=0.0, low=0.0,
                 doc="the coating's GGX roughness (pbrt's roughness, remapped or not); 0: smooth")


def check_walks(values) -> str | None:
    for name in ("maxdepth", "nsamples"):
        if np.any(values[name] != np.round(values[name])):
            return f"{name}: must be a whole number, got {np.ravel(values[name])[0]:g}"
    return None


_ROUGH = {p.name: p.slot for p in RoughConductor.params}     # the base's slots (kernels/layered.cl)

# the random walks, whose metal base is a roughconductor's (kernels/layered.cl)
LAYERED_FILES = ("bsdfs/roughconductor.cl", "layered.cl")


class CoatedDiffuse(BSDFType):
    name = "coateddiffuse"
    formats = {"pbrt": "coateddiffuse"}
    format_only = (PBRT_COATING_ETA, *pbrt_roughness(), PBRT_REMAP)
    examples = ({"reflectance": [0.7, 0.3, 0.1]}, {"reflectance": [0.2, 0.6, 0.9], "alpha": 0.1},
                {"reflectance": 0.8, "alpha": 0.4, "thickness": 0.3, "eta": 1.33},
                {"reflectance": 0.5, "alpha": 0.2, "thickness": 0.5, "albedo": [0.9, 0.5, 0.2], "g": 0.4, "nsamples": 2})
    estimated = True
    requires = LAYERED_FILES
    params = in_slots((
        Param("reflectance", "color", default=0.5, high=1.0, doc="the base's albedo", slot="p0.xyz", pbrt="reflectance",
              from_pbrt=pbrt_clamped),
        _ALPHA,
        Param("eta", "number", default=1.5, low=1.0001, high=10.0, doc="the coating's IOR", pbrt_from="eta"),
    ) + _LAYER_PARAMS, alpha="p0.w", eta="p1.x", thickness="p1.y", g="p1.z", maxdepth="p1.w", albedo="p2.xyz",
        nsamples="p2.w")
    doc = ("pbrt-v4's coateddiffuse: a diffuse base under a smooth or rough dielectric coating, "
           "light followed between them by random walks (Guo et al. 2018)")

    def check(self, values):
        return check_walks(values)

    def from_pbrt(self, values, given, warn):
        """pbrt-v4's coateddiffuse, its coating isotropic: alpha the mean of pbrt's two."""
        au, av = pbrt_alphas(given)
        if not math.isclose(au, av, rel_tol=1e-6):
            warn(f"pathtrace's coateddiffuse coating is isotropic; it uses alpha {(au + av) / 2:.3g}")
        alpha = (au + av) / 2
        return self.name, {**values, "eta": pbrt_coating_eta(given, "eta", warn),
                           "alpha": min(alpha, 1.0) if alpha >= SMOOTH_ALPHA else 0.0}

    def continuation(self, values):
        return np.maximum(np.max(values["reflectance"], axis=-1), 0.1)


class CoatedConductor(BSDFType):
    name = "coatedconductor"
    formats = {"pbrt": "coatedconductor"}
    # the coating's and the metal's parameters prefixed interface. and conductor.
    format_only = (replace(PBRT_COATING_ETA, pbrt="interface.eta"), *pbrt_metal_params("conductor."),
                   *pbrt_roughness("interface."), *pbrt_roughness("conductor."), PBRT_REMAP)
    # behind a mirror base, f is estimated by the coating's transmission towards wi alone (no
    # MIS): its heavy tail needs more walks per estimate for a quadrature to find its mean
    examples = ({"material": "Au", "alpha": 0.2, "nsamples": 16}, {"material": "Cu", "conductor_alpha": 0.3},
                {"material": "Al", "alpha": 0.1, "conductor_alpha": 0.2, "alpha_v": 0.3, "thickness": 0.2,
                 "albedo": [0.8, 0.6, 0.3], "g": -0.3})
    estimated = True
    requires = LAYERED_FILES
    # the base is read as a roughconductor (kernels/layered.cl), in its slots
    _BASE = {"eta": "eta", "k": "k", "alpha": "conductor_alpha", "alpha_v": "conductor_alpha_v",
             "specular_reflectance": "specular_reflectance", "distribution": "distribution"}
    reads_as = {"roughconductor": _BASE}
    params = in_slots((
        # material, or eta and k: the base's metal, which pbrt-v4 names conductor.eta and conductor.k
        *(replace(p, pbrt_from=f"conductor.{p.pbrt_from}") if p.pbrt_from else p for p in METAL_PARAMS),
        replace(_ALPHA, pbrt_from="interface.roughness"),
        Param("alpha_v", "number", default=0.0, low=0.0, high=1.0,
              doc="the coating's roughness along the bitangent; alpha where left out",
              pbrt_from="interface.vroughness"),
        Param("interface_eta", "number", default=1.5, low=1.0001, high=10.0, doc="the coating's IOR",
              pbrt_from="interface.eta"),
        Param("conductor_alpha", "number", default=0.0, low=0.0, high=1.0,
              doc="the metal's GGX roughness along the tangent; 0: a mirror", pbrt_from="conductor.roughness"),
        Param("conductor_alpha_v", "number", default=0.0, low=0.0, high=1.0,
              doc="the metal's roughness along the bitangent; conductor_alpha where left out",
              pbrt_from="conductor.vroughness"),
    ) + _LAYER_PARAMS, conductor_alpha=_ROUGH["alpha"], conductor_alpha_v=_ROUGH["alpha_v"],
        interface_eta="table[0]", g="table[1]", maxdepth="table[2]", nsamples="table[3]", alpha="table[4]",
        alpha_v="table[5]", thickness="table[6]", albedo="table[7:10]")
    derived = (Slot("specular_reflectance", _ROUGH["specular_reflectance"],
                    "1: the base roughconductor's factor on its reflectance, none here"),
               Slot("distribution", _ROUGH["distribution"], "0: the base is GGX's"))
    doc = ("pbrt-v4's coatedconductor: a smooth or rough metal under a smooth or rough dielectric "
           "coating, light followed between them by random walks (Guo et al. 2018)")
    variant_defines = ("ANISOTROPIC",)

    def from_pbrt(self, values, given, warn):
        """pbrt-v4's coatedconductor: its metal copper by default, or of a `reflectance`."""
        coating = pbrt_rough(pbrt_alphas(given, "interface.")) or {"alpha": 0.0, "alpha_v": 0.0}
        base = pbrt_rough(pbrt_alphas(given, "conductor.")) or {"alpha": 0.0, "alpha_v": 0.0}
        return self.name, {**values, **pbrt_metal(given, "conductor."), "alpha": coating["alpha"],
                           "alpha_v": coating["alpha_v"], "conductor_alpha": base["alpha"],
                           "conductor_alpha_v": base["alpha_v"],
                           "interface_eta": pbrt_coating_eta(given, "interface.eta", warn)}

    def resolve(self, values):
        values = resolve_metal(super().resolve(values))
        for v, u in (("alpha_v", "alpha"), ("conductor_alpha_v", "conductor_alpha")):
            if v not in values:
                values[v] = values.get(u, 0.0)
        return values

    def check(self, values):
        for u, v in (("alpha", "alpha_v"), ("conductor_alpha", "conductor_alpha_v")):
            if np.any((values[u] == 0) != (values[v] == 0)):
                return f"{u} and {v}: both 0 (smooth) or neither"
        return check_walks(values)

    def defines(self, rows):
        apart = [read_slot(rows, self.slots()[u]) != read_slot(rows, self.slots()[v])
                 for u, v in (("conductor_alpha", "conductor_alpha_v"), ("alpha", "alpha_v"))]
        return ("ANISOTROPIC",) if np.any(apart[0] | apart[1]) else ()

    def row_flags(self, values, n):
        delta = (values["alpha"] == 0) & (values["conductor_alpha"] == 0) & np.all(values["albedo"] == 0, axis=-1)
        return np.where(np.broadcast_to(delta, n), DELTA, 0).astype(np.int32)

    def pack(self, values, rows):
        super().pack(values, rows)
        write_slot(rows, self.slots()["specular_reflectance"], 1.0)
        write_slot(rows, self.slots()["distribution"], 0.0)
