"""Study (docs/notes/performance-2026-12.md, 2026-12-03, thirty-second session): what each feature
group costs the generic program without media on a GPU. `python
docs/notes/studies/generic_ablation.py --without textures,normal_maps bench --device gpu --program
generic ...` builds that generic program without those groups (Features fields: shapes, masks,
textures, normal_maps, light_tree, instances); each variant needs a cache folder of its own
(XDG_CACHE_HOME), as they share a cache entry. A scene that needs a group left out cannot be
rendered by it. Leaving out `instances` needs kernels/bvh.cl's trace_ray to take its generic
branch only `#if defined(GENERIC) && defined(INSTANCES)` (the study ran every variant from a copy
so edited; a generic program always has INSTANCES); `textures` cannot go without `masks` and
`normal_maps`, which read textures."""
import sys
from dataclasses import replace
from pathtrace.device import features as F

EMPTY = {"shapes": (), "textures": (), "masks": False, "normal_maps": False, "light_tree": False,
         "instances": False}
if "--without" in sys.argv:
    k = sys.argv.index("--without")
    left_out = sys.argv[k + 1].split(",")
    del sys.argv[k:k + 2]
    full = F.Features.generic_program

    def ablated(media):
        f = full(media)
        return f if media else replace(f, **{name: EMPTY[name] for name in left_out})
    F.Features.generic_program = staticmethod(ablated)
from pathtrace.cli.main import main
sys.exit(main(sys.argv[1:]))
