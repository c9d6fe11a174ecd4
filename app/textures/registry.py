"""The registry of texture types: each type's tag, and the kernels' dispatch (eval_leaf_texture,
eval_input, eval_combined, eval_texture) generated from it. Adding a texture type takes its
kernel file (kernels/textures/<name>.cl), its host class (a TextureType: its parameters with
their names in the formats, app/parameters.py, pack, mean, bounds and examples) and its entry
here; the TOML and Mitsuba readers read it through its declarations (pbrt-v4's textures, with
their own uv mappings, are mapped by hand in app/scene/pbrt/materials.py).
Its examples put it through tests/test_texture_conformance.py (the kernel's values against its
mean and bounds) by its registration alone."""

from pathtrace.textures.bitmap import Bitmap
from pathtrace.textures.checkerboard import Checkerboard
from pathtrace.textures.clamp import Clamp
from pathtrace.textures.constant import Constant
from pathtrace.textures.mix import Mix
from pathtrace.textures.scale import Scale
from pathtrace.textures.texture import KINDS

TEXTURES = {cls.name: cls() for cls in (Constant, Bitmap, Checkerboard, Scale, Mix, Clamp)}
TAGS = {name: i for i, name in enumerate(TEXTURES)}
KINDS.update(TEXTURES)         # what Texture.kind looks up
# the registers of a texture program (kernels/texture.cl): enough for any chain, and for a tree of
# combining textures of up to 2^(TEXTURE_REGISTERS - 1) of them in the worst (balanced) shape
TEXTURE_REGISTERS = 8


def kernel_parts(names) -> list:
    """(name, source) of the texture kernels for the types `names`, in the order they compile:
    kernels/texture.cl, the types that read no other texture and their dispatch, then the
    types that combine them, their dispatch and eval_texture, which runs a combining texture's
    program. Empty when `names` is: a scene without textures compiles none of it."""
    if not names:
        return []
    leaves = [n for n in TEXTURES if n in names and TEXTURES[n].leaf]
    combined = [n for n in TEXTURES if n in names and not TEXTURES[n].leaf]
    tags = "".join(f"#define TEXTURE_{n.upper()} {TAGS[n]}\n" for n in TEXTURES) \
        + f"#define TEXTURE_REGISTERS {TEXTURE_REGISTERS}\n"
    # each combining type's inputs by name, <TYPE>_INPUT_<NAME>: their order in its declaration
    tags += "".join(f"#define {n.upper()}_INPUT_{name.upper()} {k}\n"
                    for n, t in TEXTURES.items() for k, name in enumerate(t.inputs))

    def dispatch(signature, types, args):
        cases = "".join(f"    case TEXTURE_{n.upper()}: return eval_{n}({args});\n" for n in types)
        return (f"{signature}\n{{\n" + ("    const global Texture *t = &sc->textures[i];\n" if "int i" in signature else "")
                + f"    switch (t->type) {{\n{cases}    default: return (float3)(0.0f);\n    }}\n}}\n")
    # eval_leaf_texture stays inlined even in a GPU's generic program: NVIDIA's driver 580 built
    # a generic program with it called (DISPATCH) that kept 101 to 765 of a pixel's 256 samples,
    # where inlining it alone of the dispatch functions made the program keep every sample
    # (docs/notes/performance-2026-11.md, 2026-11-30 eleventh session)
    leaf_dispatch = (dispatch("float3 eval_leaf_texture(const SceneData *sc, int i, float2 uv)", leaves, "sc, t, uv")
                     + "float3 eval_input(const SceneData *sc, const global Texture *t, int k, float2 uv, const float3 *r)\n"
                       "{\n    int i = t->input[k];\n"
                       "    return i >= 0 ? eval_leaf_texture(sc, i, uv) : (i == -1 ? t->value[k].xyz : r[-2 - i]);\n}\n")
    if not combined:
        full = ("DISPATCH float3 eval_texture(const SceneData *sc, int i, float2 uv)\n{\n"
                "    return eval_leaf_texture(sc, i, uv);\n}\n")
    else:
        full = (dispatch("DISPATCH float3 eval_combined(const SceneData *sc, const global Texture *t, float2 uv, const float3 *r)",
                         combined, "sc, t, uv, r")
                + "DISPATCH float3 eval_texture(const SceneData *sc, int i, float2 uv)\n{\n"
                  "    int j = sc->textures[i].program;\n"
                  "    if (j < 0)\n        return eval_leaf_texture(sc, i, uv);\n"
                  "    float3 r[TEXTURE_REGISTERS];\n    int top = 0;\n"
                  "    for (;; ++j) {\n"
                  "        const global Texture *t = &sc->textures[j];\n"
                  "        float3 v = eval_combined(sc, t, uv, r);\n"
                  "        if (j == i)\n            return v;\n"
                  "        top -= (t->input[0] < -1) + (t->input[1] < -1) + (t->input[2] < -1);\n"
                  "        r[top++] = v;\n    }\n}\n")
    here = "app/textures/registry.py: kernel_parts"
    return ([(here, tags), ("texture.cl", None)] + [(f"textures/{n}.cl", None) for n in leaves]
            + [(here, leaf_dispatch)] + [(f"textures/{n}.cl", None) for n in combined]
            + [(here, full)])
