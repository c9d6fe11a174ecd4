"""The registry of material types: each type's tag, and the kernels' dispatch (eval_bsdf,
pdf_bsdf, sample_bsdf) generated from it. Adding a material takes its kernel file
(kernels/bsdfs/<name>.cl), its host BSDFType (its parameters with their names in the formats,
app/parameters.py, their slots and those it derives, which its kernel reads through the accessors
tag_source generates, checks and examples) and its entry here; the readers read it through
its declarations (pbrt-v4's materials that map onto several types are still mapped by hand, in
app/scene/pbrt/materials.py). Its
examples put it through tests/test_bsdfs.py (chi-square of its sampling against its
pdf, the pdf's normalisation, the sample weight, reciprocity, energy) by its registration alone."""

from pathtrace.materials.basic import Black, Diffuse, Null, Phong
from pathtrace.materials.blend import BlendBSDF
from pathtrace.materials.bsdf import DELTA
from pathtrace.materials.conductor import Conductor, RoughConductor
from pathtrace.materials.dielectric import Dielectric, RoughDielectric, ThinDielectric
from pathtrace.materials.diffusetransmission import DiffuseTransmission
from pathtrace.materials.layered import CoatedConductor, CoatedDiffuse
from pathtrace.materials.plastic import Plastic, RoughPlastic
from pathtrace.materials.principled import Principled
from pathtrace.device.dispatch import dispatch_glue, switch_body
from pathtrace.device.slots import slot_accessor

BSDFS = {cls.name: cls() for cls in (Black, Diffuse, Phong, Conductor, RoughConductor,
                                     Dielectric, RoughDielectric, ThinDielectric, Plastic,
                                     RoughPlastic, DiffuseTransmission, CoatedDiffuse, Null, BlendBSDF,
                                     CoatedConductor, Principled)}
TAGS = {name: i for i, name in enumerate(BSDFS)}


def tag_source() -> str:
    """The BSDF_<NAME> tags of every type, which the kernel files may name, and the accessors
    <TYPE>_<NAME>(m) of each type's slots, its parameters' (Param.slot) and those pack() derives
    (BSDFType.derived), so that the slots are defined once, on the host: the kernels read a
    material's p0..p2 and table through them alone (tests/test_types.py)."""
    tags = "".join(f"#define BSDF_{name.upper()} {TAGS[name]}\n" for name in BSDFS)
    return tags + "".join(f"#define {name.upper()}_{slot_name.upper()}(m) {slot_accessor(slot)}\n"
                          for name, b in BSDFS.items() for slot_name, slot in b.slots().items())


# The type a generic program inlines before its dispatch's call (kernels/inlining.h: DISPATCH):
# the commonest, whose call would cost most scenes a call per vertex
FAST_PATH = "diffuse"


# f and its pdf in one switch, for a light sample (kernels/integrator.cl): a warp whose lanes shade
# several BSDFs runs each one's code once, where eval_bsdf and pdf_bsdf each run it. A generic
# program, whose dispatch is a call on GPUs, makes the two calls it made before.
EVAL_PDF = """float3 eval_pdf_bsdf(MaterialRef m, float3 wo, float3 wi, float *pdf)
#ifdef GENERIC
{{
    *pdf = pdf_bsdf(m, wo, wi);
    return eval_bsdf(m, wo, wi);
}}
#else
{}#endif
"""


def dispatch_source(names=None) -> str:
    """The eval/pdf/sample dispatch of kernels/bsdf.cl over the types `names` (None: all). In a
    generic program, where the dispatch is a call (kernels/inlining.h), FAST_PATH is tested
    first, inlined."""
    with_kernel = [n for n in _with_kernel(names) if not BSDFS[n].resolved_first]
    # a type whose every lobe is a delta has no eval or pdf (both 0): it provides sample only
    smooth = [n for n in with_kernel if not BSDFS[n].flags & DELTA]

    def dispatch(signature, call, args, types, default):
        return dispatch_glue(signature, "m->type", {f"BSDF_{n.upper()}": f"{call.format(n)}{args}" for n in types},
                             default, f"BSDF_{FAST_PATH.upper()}")
    return (dispatch("float3 eval_bsdf(MaterialRef m, float3 wo, float3 wi)", "eval_{}", "(m, wo, wi)", smooth,
                     "(float3)(0.0f)")
            + dispatch("float pdf_bsdf(MaterialRef m, float3 wo, float3 wi)", "pdf_{}", "(m, wo, wi)", smooth, "0.0f")
            + EVAL_PDF.format(switch_body("m->type", {f"BSDF_{n.upper()}": f"(*pdf = pdf_{n}(m, wo, wi), eval_{n}(m, wo, wi))"
                                                      for n in smooth}, "(*pdf = 0.0f, (float3)(0.0f))"))
            + dispatch("int sample_bsdf(MaterialRef m, float3 wo, float3 u, BSDFSample *s)", "sample_{}",
                       "(m, wo, u, s)", with_kernel, "0"))


def _with_kernel(names):
    return [n for n, b in BSDFS.items() if b.kernel and (names is None or n in names)]


def kernel_files(names=None) -> list[str]:
    """The kernel files of the types `names` (None: all), in registry order, each after the
    files it requires (BSDFType.requires), every file once."""
    files = []
    for n in _with_kernel(names):
        files += [f for f in (*BSDFS[n].requires, f"bsdfs/{n}.cl") if f not in files]
    return files
