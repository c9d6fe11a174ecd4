"""Bisects the generic program's miscount on NVIDIA (docs/notes/performance-2026-11.md,
2026-11-30, tenth session): the Cornell box (tests/scenes/cbox.xml, 24x24, 4 launches of 64
spp) rendered by the generic program, built untuned with the dispatch functions named on the
command line inlined (their DISPATCH attribute, kernels/inlining.h, dropped), and by the
scene's own program; prints each program's samples kept per pixel (min, max; a sound program
keeps 256 everywhere) and its mean radiance per sample. The eleventh session's table (the same
note) was run at commit 10962f8, where eval_leaf_texture was one of the dispatch functions; it
is inlined since (app/textures/registry.py).
python docs/notes/studies/generic_counts.py [DEVICE] [FUNCTION ...], DEVICE as --device takes
it (default gpu), a FUNCTION among the dispatch functions below, or all of them with `all`."""
import os
import sys
import tempfile

import pyopencl as cl

os.environ["PATHTRACE_CACHE"] = tempfile.mkdtemp(prefix="generic-counts-")   # nothing from earlier builds
import pathtrace.device.opencl as opencl                                          # noqa: E402
from pathtrace.filters import PixelFilter                                         # noqa: E402
from pathtrace.rendering.renderer import Renderer                                 # noqa: E402
from pathtrace.scene import load_scene                                            # noqa: E402

DISPATCH = ("eval_bsdf", "pdf_bsdf", "sample_bsdf", "sample_light_of_type", "eval_combined",
            "eval_texture")
device = sys.argv[1] if len(sys.argv) > 1 else "gpu"
inlined = DISPATCH if sys.argv[2:] == ["all"] else tuple(sys.argv[2:])
unknown = set(inlined) - set(DISPATCH)
if unknown:
    sys.exit(f"not a dispatch function: {', '.join(map(repr, sorted(unknown)))} (they are: {', '.join(DISPATCH)})")

source_of = opencl.kernel_source


def kernel_source(*args, **kwargs):
    """The kernels' source with the named dispatch functions' DISPATCH attribute dropped."""
    source = source_of(*args, **kwargs)
    for name in inlined:
        for kind in ("float3", "float", "int"):
            source = source.replace(f"DISPATCH {kind} {name}(", f"{kind} {name}(")
    return source


opencl.kernel_source = kernel_source
opencl.build_for_occupancy = lambda context, dev, source, options: (
    cl.Program(context, source).build(options=options, devices=[dev]), options)      # untuned: one build
backend = opencl.choose_device(device)
scene = load_scene("tests/scenes/cbox.xml").with_settings(filter=PixelFilter(), max_depth=5, integrator="path",
                                                          seed=99)
print(f"{backend.device.name}; inlined: {', '.join(inlined) or 'none'}", flush=True)
for mode in ("generic", "specialised"):
    r = Renderer(backend.with_mode(mode), scene, 24, 24)
    for _ in range(4):
        r.add_samples(64)
    r.finish()
    kept = r.read_sum()[..., 3]
    print(f"{mode}: kept {kept.min():.0f} to {kept.max():.0f} of {r.samples} per pixel, "
          f"mean radiance per sample {r.mean().mean():.5f}", flush=True)
