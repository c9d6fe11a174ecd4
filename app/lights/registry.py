"""The registry of light types: each type's tag, and the kernels' dispatch (sample_light_of_type)
generated from it. Adding a delta light type takes its kernel file (kernels/lights/<name>.cl)
and its host module in app/lights (a DeltaLight with its parameters declared for the three
formats, app/parameters.py, and its examples), which the registry finds by itself; the scene
readers read it through its declarations, and its examples put it through
tests/test_light_conformance.py. Area lights and the
environment are always compiled in, as the integrator weighs the emitters its paths hit against
them; the delta lights only into the programs of scenes that have them."""

import importlib
import pkgutil
from pathlib import Path

from pathtrace.lights.light import DeltaLight
from pathtrace.device.dispatch import dispatch_glue, switch_body
from pathtrace.device.slots import slot_accessor

# the modules of app/lights that are the interface and its tables, not light types
INTERFACE = ("area", "light", "registry", "table", "tree")


def _delta_light_types() -> list:
    """The DeltaLight types that the modules of app/lights define, in their modules' order (the
    first three as they were listed by hand: point, spot, directional)."""
    first = ("point", "spot", "directional")
    modules = sorted((m.name for m in pkgutil.iter_modules([str(Path(__file__).parent)]) if m.name not in INTERFACE),
                     key=lambda n: (first.index(n) if n in first else len(first), n))
    found = []
    for name in modules:
        module = importlib.import_module(f"pathtrace.lights.{name}")
        found += [c for c in vars(module).values() if isinstance(c, type) and issubclass(c, DeltaLight)
                  and c is not DeltaLight and c.__module__ == module.__name__]
    return found


DELTA_LIGHTS = {cls.name: cls for cls in _delta_light_types()}
LIGHTS = ("area", "environment", *DELTA_LIGHTS)
TAGS = {name: i for i, name in enumerate(LIGHTS)}
EMITTERS = {"area": "pdf_area_emission(sc, l->prim, n, w)", "point": "pdf_point_emission(l, w)",
            "spot": "pdf_spot_emission(l, w)", "goniometric": "pdf_goniometric_emission(l, w)",
            "projection": "pdf_projection_emission(l, w)", "environment": "pdf_environment_emission(sc, p, -w)",
            "directional": "0.0f"}
"""How each type of light starts light subpaths in bidirectional path tracing (kernels/bdpt.cl):
the density of the direction w it leaves in towards a point of normal n, as a call (a
directional light's one direction is a delta). Lights at infinity leave a disk across the scene
(kernels/lights.cl: leave_world_disk). Every type has one (tests/test_bdpt.py): BDPT's weights
count light subpaths from every light."""


# The type a generic program samples inlined before its dispatch's call: the commonest, whose
# call would cost most scenes a call per vertex
FAST_PATH = "area"


def kernel_parts(names=None, tree: bool = False, bidirectional: bool = False) -> list:
    """(name, source) of the light kernels of a program whose delta light types are `names`
    (None: all), in the order they compile: the tags, the interface, the light tree's traversal
    (for a scene that has one), each type's file, and the dispatch over them (with
    `bidirectional`, also over the light they emit: EMITTERS)."""
    used = [n for n in LIGHTS if n in ("area", "environment") or names is None or n in names]
    tags = "".join(f"#define LIGHT_{n.upper()} {TAGS[n]}\n" for n in LIGHTS) + f"#define LIGHT_TREE_ROOT {len(LIGHTS)}\n"
    # each type's slots, read through <NAME>_LIGHT_<SLOT>(l) (app/device/slots.py)
    tags += "".join(f"#define {n.upper()}_LIGHT_{s.name.upper()}(l) {slot_accessor(s.slot, 'l')}\n"
                    for n, cls in DELTA_LIGHTS.items() for s in cls.slots)

    # in a generic program FAST_PATH is sampled inlined before the dispatch's call (dispatch_glue)
    dispatch = dispatch_glue("int sample_light_of_type(const SceneData *sc, const RenderParams *p, const global Light *l,\n"
                             "                         float3 x, float3 n, float2 u, LightSample *ls)", "l->type",
                             {f"LIGHT_{n.upper()}": f"sample_{n}_light(sc, p, l, x, n, u, ls)" for n in used}, "0",
                             f"LIGHT_{FAST_PATH.upper()}")
    if bidirectional:
        emitters = [n for n in used if n in EMITTERS]
        dispatch += ("int emit_light_of_type(const SceneData *sc, const RenderParams *p, const global Light *l, float4 u,\n"
                     "                       LightEmission *e)\n"
                     + switch_body("l->type", {f"LIGHT_{n.upper()}": f"emit_{n}_light(sc, p, l, u, e)" for n in emitters}, "0")
                     + "float pdf_emission_of_type(const SceneData *sc, const RenderParams *p, const global Light *l, float3 n,\n"
                     "                            float3 w)\n"
                     + switch_body("l->type", {f"LIGHT_{n.upper()}": EMITTERS[n] for n in emitters}, "0.0f"))
    files = [f"lights/{n}.cl" for n in used]
    here = "app/lights/registry.py: kernel_parts"
    return ([(here, tags), ("lights.cl", None)] + ([("light_tree.cl", None)] if tree else [])
            + [(f, None) for f in files] + [(here, dispatch)])
