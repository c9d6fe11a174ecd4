"""The registry of light types: each type's tag, and the kernels' dispatch (sample_light_of_type)
generated from it. Adding a light type takes its kernel file (kernels/lights/<name>.cl), its host
module (with its examples) and its entry here, and each scene reader's mapping of its format's
light onto it (written by hand in app/scene/toml_reader.py, mitsuba.py and pbrt/reader.py); its
examples put it through tests/test_light_conformance.py by its registration alone. Area lights and the
environment are always compiled in, as the integrator weighs the emitters its paths hit against
them; the delta lights only into the programs of scenes that have them."""

from pathtrace.lights.directional import DirectionalLight
from pathtrace.lights.point import PointLight
from pathtrace.lights.spot import SpotLight

DELTA_LIGHTS = {cls.name: cls for cls in (PointLight, SpotLight, DirectionalLight)}
LIGHTS = ("area", "environment", *DELTA_LIGHTS)
TAGS = {name: i for i, name in enumerate(LIGHTS)}


def kernel_parts(names=None, tree: bool = False) -> list:
    """(name, source) of the light kernels of a program whose delta light types are `names`
    (None: all), in the order they compile: the tags, the interface, the light tree's traversal
    (for a scene that has one), each type's file, and the dispatch over them."""
    used = [n for n in LIGHTS if n in ("area", "environment") or names is None or n in names]
    tags = "".join(f"#define LIGHT_{n.upper()} {TAGS[n]}\n" for n in LIGHTS) + f"#define LIGHT_TREE_ROOT {len(LIGHTS)}\n"

    def switch(call, default):
        cases = "".join(f"    case LIGHT_{n.upper()}: return {call.format(n)};\n" for n in used)
        return f"    switch (l->type) {{\n{cases}    default: return {default};\n    }}\n"
    dispatch = ("DISPATCH int sample_light_of_type(const SceneData *sc, const RenderParams *p, const global Light *l,\n"
                "                         float3 x, float3 n, float2 u, LightSample *ls)\n{\n"
                + switch("sample_{}_light(sc, p, l, x, n, u, ls)", "0") + "}\n")
    files = [f"lights/{n}.cl" for n in used]
    here = "app/lights/registry.py: kernel_parts"
    return ([(here, tags), ("lights.cl", None)] + ([("light_tree.cl", None)] if tree else [])
            + [(f, None) for f in files] + [(here, dispatch)])
