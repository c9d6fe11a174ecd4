"""The registry of texture types: each type's tag, and the kernels' dispatch (eval_leaf_texture,
eval_input, eval_texture) generated from it, so that adding a texture type is one kernel file
(kernels/textures/<name>.cl) and one entry here."""

from pathtrace.textures.bitmap import Bitmap
from pathtrace.textures.checkerboard import Checkerboard
from pathtrace.textures.constant import Constant
from pathtrace.textures.mix import Mix
from pathtrace.textures.scale import Scale

TEXTURES = {cls.name: cls() for cls in (Constant, Bitmap, Checkerboard, Scale, Mix)}
TAGS = {name: i for i, name in enumerate(TEXTURES)}


def kernel_parts(names) -> list:
    """(name, source) of the texture kernels for the types `names`, in the order they compile:
    kernels/texture.cl, the types that read no other texture and their dispatch, then the
    types that combine them and the full dispatch. Empty when `names` is: a scene without
    textures compiles none of it."""
    if not names:
        return []
    leaves = [n for n in TEXTURES if n in names and TEXTURES[n].leaf]
    combined = [n for n in TEXTURES if n in names and not TEXTURES[n].leaf]
    tags = "".join(f"#define TEXTURE_{n.upper()} {TAGS[n]}\n" for n in TEXTURES)

    def dispatch(signature, types):
        cases = "".join(f"    case TEXTURE_{n.upper()}: return eval_{n}(sc, t, uv);\n" for n in types)
        return (f"{signature}\n{{\n    const global Texture *t = &sc->textures[i];\n"
                f"    switch (t->type) {{\n{cases}    default: return (float3)(0.0f);\n    }}\n}}\n")
    leaf_dispatch = (dispatch("DISPATCH float3 eval_leaf_texture(const SceneData *sc, int i, float2 uv)", leaves)
                     + "float3 eval_input(const SceneData *sc, const global Texture *t, int k, float2 uv)\n{\n"
                       "    return t->input[k] >= 0 ? eval_leaf_texture(sc, t->input[k], uv) : t->value[k].xyz;\n}\n")
    full = dispatch("DISPATCH float3 eval_texture(const SceneData *sc, int i, float2 uv)", leaves + combined)
    here = "app/textures/registry.py: kernel_parts"
    return ([(here, tags), ("texture.cl", None)] + [(f"textures/{n}.cl", None) for n in leaves]
            + [(here, leaf_dispatch)] + [(f"textures/{n}.cl", None) for n in combined]
            + [(here, full)])
