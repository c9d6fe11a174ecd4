"""The options that several commands share, their value parsers (each a line naming the option
and the problem, through argparse), and the scene settings they change."""

import argparse
from dataclasses import replace

from pathtrace.errors import UserError, short, warn
from pathtrace.rendering.choices import (FILTERS, INTEGRATORS, LIGHT_SAMPLERS, MAX_PATH_QUEUE, PATH_QUEUE_AUTO,
                                         RUSSIAN_ROULETTE, TONEMAPS)

# The epilog of the commands that take a scene, written out only when help is shown: the names
# of the built-in scenes come from their module, which no other command need import
SCENES_EPILOG = "(the scenes)"


def image_size(text):
    """--size: WIDTHxHEIGHT, each 1 to 16384 (the examples take it too)."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{short(text)} is not WIDTHxHEIGHT, e.g. 1920x1080") from None
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise argparse.ArgumentTypeError(f"{short(text)}: width and height must be 1 to 16384")
    return w, h


def _count(text):
    """A primitive count: digits with an optional k or M suffix, 2 to 100M."""
    digits, suffix = (text[:-1], text[-1]) if text[-1:] in ("k", "M") else (text, "")
    if not digits.isdigit() or not 2 <= int(digits) * {"": 1, "k": 1000, "M": 10**6}[suffix] <= 10**8:
        raise argparse.ArgumentTypeError(f"{short(text)} is not a count from 2 to 100M (e.g. 64k, 1M)")
    return int(digits) * {"": 1, "k": 1000, "M": 10**6}[suffix]


def _int_range(low, high=None):
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{short(text)} is not an integer") from None
        if value < low or (high is not None and value > high):
            bound = f"at least {low}" if high is None else f"{low} to {high}"
            raise argparse.ArgumentTypeError(f"{value} is out of range (must be {bound})")
        return value
    return parse


def _finite(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{short(text)} is not a number") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"{short(text)} is not a finite number")
    return value


def _exposure(text):
    value = _finite(text)
    if abs(value) > 100:     # 2^100 already saturates every pixel; 2^1100 overflows a double
        raise argparse.ArgumentTypeError(f"{value} stops is out of range (must be -100 to 100)")
    return value


def add_output_options(p: argparse.ArgumentParser):
    """Options of the commands that write images (render, farm render)."""
    p.add_argument("--exposure", type=_exposure, default=0.0, metavar="EV",
                   help="exposure in stops, -100 to 100, for .png/.jpg (default 0)")
    p.add_argument("--tonemap", choices=TONEMAPS, default="standard",
                   help="tone curve for .png/.jpg (default standard: clip at 1)")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress bar, and (render) no line per phase with its time")


def add_program_option(p: argparse.ArgumentParser, default: str):
    from pathtrace.device.programs import PROGRAM_ENV, PROGRAM_MODES
    p.add_argument("--program", choices=PROGRAM_MODES,
                   help="which kernels render: auto (a generic program, built once and cached, until "
                        "the scene's own is built in the background), specialised (wait for the "
                        "scene's own: repeatable renders) or generic (never build another for the path tracer; "
                        "bdpt and ptracer, which it does not hold, build their own); default "
                        f"{PROGRAM_ENV} if set, else {default}")


def add_render_options(p: argparse.ArgumentParser, device: bool = True, queue_auto: bool = True):
    """Options shared by everything that renders a scene (the farm's workers choose their own
    devices: device=False)."""
    if device:
        p.add_argument("--device", action="append", metavar="DEVICE",
                       help="auto (first GPU that builds the kernels, else CPU; the default), "
                            "gpu, cpu, gpu:N or cpu:N (the Nth of that kind, from 0), an index "
                            "from 'pathtrace devices', or part of a device name; render: repeat "
                            "to share the samples between devices, or 'all' for every device")
        add_program_option(p, "auto")
    p.add_argument("--size", type=image_size, metavar="WxH", help="image size (default: the scene's)")
    p.add_argument("--seed", type=_int_range(0, 2**32 - 1), help="random seed (default: the scene's)")
    p.add_argument("--max-depth", type=_int_range(0, 2**31 - 1), metavar="N",
                   help="longest path in vertices, 1 = emitters seen directly; 0 = unlimited")
    p.add_argument("--rr", choices=RUSSIAN_ROULETTE,
                   help="how paths end: throughput (Russian roulette from depth 5, the default), "
                        "albedo (the report's, at every bounce) or off (at --max-depth)")
    p.add_argument("--nee", action=argparse.BooleanOptionalAction, default=None,
                   help="next-event estimation: sample lights at every bounce, combined by MIS "
                        "(default on; --no-nee gives the report's estimator)")
    p.add_argument("--light-sampler", choices=LIGHT_SAMPLERS,
                   help="how next-event estimation chooses a light: power (in proportion to its "
                        "power), tree (by a light tree, from what it gives the shading point), or "
                        "auto (the tree from 4096 lights on; the default: the scene's)")
    p.add_argument("--integrator", choices=INTEGRATORS,
                   help="path (the path tracer, the default), bdpt (bidirectional path tracing: "
                        "caustics) or ptracer (its light tracing alone); default: the scene's")
    p.add_argument("--photon-radius", type=_photon_radius, metavar="R",
                   help="with --integrator bdpt: caustic photons, gathered within R (scene units) at "
                        "first, for what BDPT cannot find (a floor seen and lit through water); 0: none "
                        "(default: the scene's; pbrt's sppm asks for them)")
    p.add_argument("--filter", type=_pixel_filter, metavar="NAME[:RADIUS[:STDDEV]]",
                   help="pixel filter: box (radius 0.5), tent (1) or gaussian (stddev 0.5, radius 4 "
                        "stddev), radius and stddev in pixels (default: the scene's)")
    add_path_queue_option(p, auto=queue_auto)


def add_path_queue_option(p: argparse.ArgumentParser, auto: bool = True):
    p.add_argument("--path-queue", type=_path_queue if auto else _int_range(0, MAX_PATH_QUEUE),
                   metavar="N|auto" if auto else "N",
                   help="trace the paths that go on past N vertices from a queue, one vertex a pass, "
                        "so that a GPU's warps stay full where few paths go on long (the same image; "
                        "faster on some scenes, slower on others: docs/performance.md); 0 = off, the default"
                        + ("; auto: on a GPU, chosen by trial renders before the render" if auto else ""))
    p.add_argument("--path-sort", action="store_true",
                   help="with --path-queue: trace the queue's paths in the order of their rays (direction "
                        "and place), so that a GPU's warps walk the BVH together (the same image; "
                        "docs/performance.md)")


PATH_SORT_ALONE = "--path-sort sorts the continuation queue's paths: give --path-queue N (N >= 1) too"


def _path_queue(text: str) -> int:
    if text == "auto":
        return PATH_QUEUE_AUTO
    try:
        return _int_range(0, MAX_PATH_QUEUE)(text)
    except argparse.ArgumentTypeError as e:
        raise argparse.ArgumentTypeError(f"{e}; or auto") from None


def _pixel_filter(text: str):
    from pathtrace.errors import did_you_mean
    name, *numbers = text.split(":")
    if name not in FILTERS:         # worded as argparse words a bad choice of the other options
        raise argparse.ArgumentTypeError(f"invalid choice: {short(name)} (choose from "
                                         f"{', '.join(map(repr, FILTERS))}){did_you_mean(name, FILTERS)}")
    try:
        values = [float(x) for x in numbers]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{short(text)}: radius and stddev must be numbers") from None
    if len(values) > (2 if name == "gaussian" else 1):
        raise argparse.ArgumentTypeError(f"{short(text)}: too many numbers for a {short(name)} filter")
    from pathtrace.filters import PixelFilter
    try:
        return PixelFilter(name, *values).check()
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _photon_radius(text: str) -> float:
    from pathtrace.scene.meshes import MAX_COORDINATE
    try:
        radius = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{short(text)}: not a number") from None
    if not 0 <= radius <= MAX_COORDINATE:
        raise argparse.ArgumentTypeError(f"{short(text)}: give a distance in [0, {MAX_COORDINATE:g}] (0: no photons)")
    return radius


def apply_render_options(scene, args):
    s = scene.settings
    width, height = args.size or (s.width, s.height)
    max_depth = s.max_depth if args.max_depth is None else args.max_depth
    rr = args.rr or s.russian_roulette
    changes = dict(width=width, height=height, max_depth=max_depth, russian_roulette=rr,
                   seed=s.seed if args.seed is None else args.seed,
                   nee=s.nee if args.nee is None else args.nee,
                   filter=args.filter or s.filter, light_sampler=args.light_sampler or s.light_sampler,
                   path_queue=s.path_queue if args.path_queue is None else args.path_queue,
                   path_sort=s.path_sort or args.path_sort,
                   integrator=getattr(args, "integrator", None) or s.integrator,
                   photon_radius=s.photon_radius if getattr(args, "photon_radius", None) is None else args.photon_radius)
    if not replace(s, **changes).paths_end:
        raise UserError("--rr off needs --max-depth N (N >= 1), or paths would never end")
    if changes["path_sort"] and not changes["path_queue"]:
        raise UserError(PATH_SORT_ALONE)
    if getattr(args, "photon_radius", None) and changes["integrator"] != "bdpt":
        raise UserError(f"--photon-radius gathers bidirectional path tracing's caustic photons, and {scene.name} "
                        f"renders with {changes['integrator']}: give --integrator bdpt too")
    if not changes["nee"] and scene.lights:
        warn(f"{scene.name}: its {len(scene.lights)} point, spot or directional light(s) are reached by "
             f"next-event estimation only; without it (--no-nee) they light nothing")
    if getattr(args, "spp", None) is not None:
        changes["spp"] = args.spp
    return scene.with_settings(**changes)
