"""`pathtrace bench`: the command line of the benchmark tooling (app/bench/)."""

import argparse
import sys

from pathtrace.bench.default_scenes import FIRST_IMAGE_SCENES, GENERATED_FILES, TARGET_SCENES
from pathtrace.cli.options import (PATH_SORT_ALONE, _count, _int_range, add_path_queue_option, image_size,
                                   add_program_option)

def cmd_bench(args):
    from pathtrace.bench import report as bench
    from pathtrace.errors import UserError

    # each mode times something else, in a table of its own: one at a time, and none given an
    # option it would not use (--load renders at 64x64, and had taken --size without a word)
    modes = [flags for flags, on in ((("--first-image",), args.first_image), (("--load",), args.load),
                                     (("--builds",), args.builds is not None),
                                     (("--display", "--denoise"), args.display or args.denoise)) if on]
    if len(modes) > 1:
        raise UserError(f"{' or '.join(modes[0])} and {' or '.join(modes[1])} time different things, each in a "
                        "table of its own: give one")
    if args.size and (args.load or args.load_scene and not args.first_image):
        raise UserError("--size: bench --load times each scene's loading at 64x64 (64x36 for the height field), "
                        "whatever the size; leave --size out")
    timing_size = args.size or ((320, 180) if args.quick else (1280, 720))
    load_rows = None     # with --load, the generated rows --scenes names (before validate's default)
    if (args.load or args.load_scene) and not args.first_image and args.scenes:
        from pathtrace.bench.load import check_rows
        load_rows, args.scenes = check_rows(args.scenes), None
    if args.first_image:
        from pathtrace.bench import first_image
        first_image.validate(args)
    else:
        bench.validate(args)
    if args.json:
        from pathtrace.io.images import check_writable
        check_writable(args.json, "--json", formats=None)
    if args.mitsuba:
        from pathtrace.bench.mitsuba_timing import check_mitsuba
        check_mitsuba(args.mitsuba, args.mitsuba_variant)
    if args.first_image:
        print(first_image.HEADER)
        results = [r for device in args.device or ["auto"]
                   for r in first_image.run(device, args.scenes, args.load_scene or [], args.size, args.repeats,
                                            args.mitsuba, args.mitsuba_variant)]
        if args.json:
            bench.write_json(args.json, results, sys.argv[1:])
            print(f"wrote {args.json}", file=sys.stderr)
        return 0
    if args.display or args.denoise:
        print(bench.TIMING_HEADER)
        width, height = timing_size
        results = []
        if args.display:
            results += bench.run_display(args.device or ["auto"], width, height)
        if args.denoise:
            results += bench.run_denoise(width, height)
        if args.json:
            bench.write_json(args.json, results, sys.argv[1:])
            print(f"wrote {args.json}", file=sys.stderr)
        return 0
    if args.load or args.load_scene:
        from pathtrace.bench import load as load_bench
        from pathtrace.scene import load_scene
        for name in args.load_scene or []:
            load_scene(name)     # fail on a bad file before the timed runs
        print(load_bench.LOAD_HEADER)
        results = [r for device in args.device or ["auto"]
                   for r in load_bench.run_load(device, args.load_scene or [], args.repeats, args.mitsuba,
                                                args.mitsuba_variant, generated=load_rows or load_bench.GENERATED_ROWS)]
        if args.json:
            bench.write_json(args.json, results, sys.argv[1:])
            print(f"wrote {args.json}", file=sys.stderr)
        return 0
    if args.builds is not None:
        print(bench.BUILD_HEADER)
        results = bench.run_builds(args.device or ["auto"], args.builds or bench.BUILD_SIZES)
        if args.json:
            bench.write_json(args.json, results, sys.argv[1:])
            print(f"wrote {args.json}", file=sys.stderr)
        return 0
    width, height = args.size
    if args.path_sort and not args.path_queue:
        from pathtrace.errors import UserError
        raise UserError(PATH_SORT_ALONE)
    print(bench.HEADER)
    results = bench.run(args.device or ["auto"], args.scenes, args.estimator, width, height, args.spp,
                        args.together, not args.no_cold,
                        (args.mitsuba, args.mitsuba_variant) if args.mitsuba else None, args.traversal,
                        args.trace_split, args.path_queue or 0, args.rounds, args.divergence or 0,
                        path_sort=args.path_sort)
    if args.json:
        bench.write_json(args.json, results, sys.argv[1:])
        print(f"wrote {args.json}", file=sys.stderr)
    return 0


def _warp_width(text: str) -> int:
    from pathtrace.bench.divergence_stats import check_warp
    from pathtrace.errors import UserError
    width = _int_range(1)(text)
    try:
        check_warp(width)
    except UserError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    return width


def add_parser(sub):
    """The `bench` command's parser."""
    p = sub.add_parser("bench", help="time renders of the benchmark scenes (the table of the report "
                                     "pathtrace grew from)",
                       description="Times renders of the benchmark scenes, by default at 1920x1080 "
                                   "and 1000 spp: the report's estimator (Russian roulette) on the "
                                   "report's scenes, the comparison mode (max depth 8, no Russian "
                                   "roulette) on the -diffuse ones.")
    p.add_argument("--device", action="append", metavar="DEVICE",
                   help="as for render; repeat for several, or 'all' (default: auto)")
    add_program_option(p, "specialised")
    p.add_argument("--scenes", nargs="+", metavar="SCENE",
                   help="built-in names, scene files, or the scenes bench writes (" + " ".join(GENERATED_FILES)
                        + ") (default: " + " ".join(TARGET_SCENES) + "; with "
                        "--first-image: " + " ".join(FIRST_IMAGE_SCENES) + "; with --load, the generated rows: "
                        "heightfield1M meshes850)")
    p.add_argument("--estimator", action="append", metavar="EST",
                   help="rr (the report's), depth8 (comparison mode), or either with +nee "
                        "(next-event estimation); repeatable; default: depth8+nee for scenes of meshes, "
                        "depth8 for -diffuse ones, rr for the report's other scenes")
    p.add_argument("--size", type=image_size, metavar="WxH", help="default 1920x1080 (with --first-image 640x360)")
    p.add_argument("--spp", type=_int_range(1, 2**31 - 1), help="samples per pixel (default 1000)")
    p.add_argument("--together", action="store_true",
                   help="render each scene on all the --device devices at once (one row per "
                        "scene) instead of on each in turn")
    p.add_argument("--builds", nargs="*", type=_count, metavar="N",
                   help="time BVH builds instead of renders: random spheres and a height field of "
                        "N primitives each (a k or M suffix allowed; default 64k 1M 4M)")
    for flag, text in (    # what is timed instead of renders, or what more each row times or counts
            ("--display", "time the viewer's copy of the image to the host each frame (default size 1280x720)"),
            ("--denoise", "time Open Image Denoise at each quality (default size 1280x720)"),
            ("--no-cold", "skip timing the kernels' build without the cache (on NVIDIA's OpenCL it tunes "
                          "register caps, about a minute)"),
            ("--traversal", "also count, for each row, the rays per sample and the BVH nodes visited and "
                            "primitives tested per ray (three renders of 4 spp at the row's size)"),
            ("--trace-split", "also time, for each row, its depth-2 paths against the same rays traced by a "
                              "kernel that only walks the BVH: how much of the time is tracing (8 spp at the "
                              "row's size)"),
            ("--load", "time loading instead: seconds from 'pathtrace render FILE' to its first image "
                       "(1 spp) for a 1M-triangle PLY file and for 850 PLY meshes in a pbrt-v4 file"),
            ("--first-image", "time the first image instead: seconds from 'pathtrace render SCENE --spp 1' "
                              "to its image written, in fresh processes, cold (every kernel and BVH cache "
                              "empty) and warm (the caches the cold run filled), for --scenes and --load-scene")):
        p.add_argument(flag, action="store_true", help=text)
    p.add_argument("--divergence", nargs="?", const=32, type=_warp_width, metavar="WARP",
                   help="also count, for each row, how much of a warp's width the path tracer's shading "
                        "uses: per iteration of its loop, the lanes active, each branch's (BSDF type, "
                        "light type, image textures) share of the warp while it runs, the BSDF types and "
                        "materials per warp, texture lookups per ray (a render of 4 spp at the row's "
                        "size, without the path queue; warps of WARP lanes, default 32, AMD's 64: "
                        "docs/benchmarks.md)")
    p.add_argument("--load-scene", action="append", metavar="FILE",
                   help="with --load or --first-image, also time this scene file (repeatable)")
    p.add_argument("--repeats", type=_int_range(1, 100), default=3,
                   help="with --load or --first-image, the best of this many runs (default 3); "
                        "--first-image's cold figure is the median of as many runs from empty caches")
    p.add_argument("--rounds", type=_int_range(1, 100), default=1,
                   help="time each row's render this many times (and Mitsuba's, with --mitsuba) and "
                        "count the medians (default 1)")
    p.add_argument("--mitsuba", metavar="PYTHON",
                   help="also time Mitsuba 3 on the same scenes (their XML, or a twin written for "
                        "them), run by this Python (one with 'pip install mitsuba'): the depth8+nee rows, "
                        "or with --load or --first-image every row")
    p.add_argument("--mitsuba-variant", default="llvm_ad_rgb", metavar="VARIANT",
                   help="Mitsuba's variant for --mitsuba (default llvm_ad_rgb; it needs LLVM, found "
                        "through DRJIT_LIBLLVM_PATH)")
    add_path_queue_option(p)
    p.add_argument("--quick", action="store_true", help="a smoke test: 320x180, 8 spp")
    p.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    p.set_defaults(func=cmd_bench)
