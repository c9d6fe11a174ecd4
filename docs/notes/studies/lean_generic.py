"""Study (docs/notes/performance-2026-12.md, 2026-12-03): the generic program without analytic
shapes and alpha masks, against the whole generic program and the scenes' own programs:
`python docs/notes/studies/lean_generic.py [--lean] bench --device gpu --program generic ...`,
each variant with a cache folder of its own (XDG_CACHE_HOME), as the two share a cache entry."""
import sys
from dataclasses import replace
from pathtrace.device import features as F

if "--lean" in sys.argv:
    sys.argv.remove("--lean")
    full = F.Features.generic_program

    def lean(media):
        f = full(media)
        return f if media else replace(f, shapes=(), masks=False)
    F.Features.generic_program = staticmethod(lean)
from pathtrace.cli.main import main
sys.exit(main(sys.argv[1:]))
