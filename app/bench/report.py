"""`pathtrace bench`: the report's measurement (1920x1080, 1000 samples per pixel, the scenes of
docs/benchmarks.md) on each device asked for, with both estimators.

The timed region is what a user waits for once the kernels are built: the BVH build, the
uploads, every launch, and reading the image back. Compilation is timed apart, cold (no cache)
and warm (from the binary cache). A one-sample warm-up launch runs first,
outside the timed region, because some drivers (PoCL among them) finish compiling a kernel at
its first launch; it renders the scene itself, so that the kernels specialised to it are built.

With `--mitsuba PYTHON`, each row of the comparison mode with NEE (depth8+nee: max depth 8, no
Russian roulette, as Mitsuba's `path` with rr_depth beyond 8) is rendered by Mitsuba 3 too, in a
process of that Python (pathtrace.bench.mitsuba_timing), from the scene's own XML file or from its twin
written by pathtrace.scene.mitsuba_writer: the same view, size, samples and depth, its render
alone timed, beside pathtrace's render alone (the launches and the read-back, without the BVH
build and uploads): the per-sample ratio of docs/benchmarks.md. Scenes that are files written
on demand (pathtrace.bench.scenes: `tori400-textured`, `tori400-materials`, `meshes850-obj`) are named like
built-in ones.

`pathtrace bench --builds` times BVH builds instead (app/compiler/bvh.py, on each device asked for): random
spheres and a height field of triangles at 64k, 1M and 4M primitives, the median of three builds
each, with the tree's SAH cost. `--display` times the viewer's way from the device's image to
the host (docs/performance.md), and `--denoise` Open Image Denoise at each quality.
"""

import datetime
import json
import platform
import shutil
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path
from statistics import median

from pathtrace.bench.default_scenes import GENERATED_FILES, TARGET_SCENES
from pathtrace.device.opencl import build_program, built_before, choose_devices, program_entry
from pathtrace.errors import UserError
from pathtrace.rendering.choices import PATH_QUEUE_AUTO
from pathtrace.rendering.multidevice import DeviceGroup
from pathtrace.rendering.queue_plans import AUTO_PLANS
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene

COMPARISON_DEPTH = 8
ESTIMATORS = ("rr", "depth8", "rr+nee", "depth8+nee")


@dataclass
class Result:
    scene: str
    device: str
    estimator: str            # "rr": the report's (Russian roulette); "depth8": comparison mode;
                              # "+nee": with next-event estimation
    width: int
    height: int
    spp: int
    seconds: float
    msamples_per_s: float
    mrays_per_s: float
    bvh_seconds: float
    build_cold_seconds: float       # None where not measured (bench --no-cold)
    build_warm_seconds: float | None
    render_seconds: float = 0.0     # of `seconds`, the launches and reading the image back (with
                                    # --rounds, the median round's)
    render_rounds: list = None      # with --rounds N > 1: each round's render seconds
    mean: float = 0.0               # the image's mean radiance
    mitsuba_variant: str = ""       # with --mitsuba: Mitsuba 3's render of the same scene
    mitsuba_seconds: float = None   # the median of its rounds
    mitsuba_rounds: list = None     # with --rounds N > 1: each round's seconds
    mitsuba_mean: float = None
    rays_per_sample: float = None   # with --traversal (app/bench/traversal_stats.py)
    nodes_per_ray: float = None
    primitives_per_ray: float = None
    trace_split: object = None      # with --trace-split: a pathtrace.bench.trace_split.TraceSplit
    divergence: object = None       # with --divergence: a pathtrace.bench.divergence_stats.DivergenceStats
    path_queue: int = 0             # the render setting (--path-queue; -1: auto)
    path_sort: bool = False         # the render setting (--path-sort)
    queue_plan: str = ""            # with --path-queue auto: the plan its trials chose, and
                                    # each plan's fastest trial in seconds (pathtrace.rendering.renderer)


def default_estimator(scene) -> str:
    """The report's estimator on the report's scenes, the comparison mode on -diffuse ones, and
    the comparison mode with NEE on mesh scenes (as Mitsuba's side-by-side timing of them)."""
    if scene.meshes:
        return "depth8+nee"
    return "depth8" if scene.name.endswith("-diffuse") else "rr"


def estimator_settings(estimator: str) -> dict:
    """The render settings of one of ESTIMATORS."""
    settings = dict(max_depth=COMPARISON_DEPTH, russian_roulette="off") if estimator.startswith("depth8") \
        else dict(max_depth=0, russian_roulette="albedo")
    return dict(settings, nee=estimator.endswith("+nee"))


def measure(backends, scene, estimator, width, height, spp, builds, rounds: int = 1) -> Result:
    """A timed render of `scene` on `backends` together (one device, or several sharing the
    samples: pathtrace.rendering.multidevice); with rounds > 1, that many renders of the same samples,
    whose median counts."""
    scene = scene.with_settings(**estimator_settings(estimator))
    # the scene's own kernels (pathtrace.device.features), built and launched once outside the
    # timed region, and with path_queue "auto" each plan's, which its trials launch
    plans = AUTO_PLANS if scene.settings.path_queue == PATH_QUEUE_AUTO else ()
    for backend in backends:
        r = Renderer(backend, scene, 16, 16)
        r.add_samples(1)
        for plan in plans:
            r.use_queue_plan(plan)
            r.switch_when_built(wait=True)
            r.add_samples(1)
        backend.queue.finish()
    start = time.perf_counter()
    group = DeviceGroup(backends, scene, width, height)
    setup = time.perf_counter() - start
    times = []
    for k in range(rounds):
        if k:                       # the same samples again
            for renderer in group.renderers:
                renderer.reset()
        rendering = time.perf_counter()
        # path_queue "auto": its trials in the first round, their samples kept as a render keeps
        # them (api.render), so that every round draws spp samples; later rounds take the plan
        group.choose_queue_plans(spp, keep_up_to=spp)
        group.render(spp, launch_seconds=0.5)
        image = group.mean()
        times.append(time.perf_counter() - rendering)
    render_seconds = median(times)
    seconds = setup + render_seconds
    rays = group.rays_traced()
    names = [b.device.describe() for b in backends]
    device = names[0] if len(names) == 1 else f"{len(names)}x {names[0]}" if len(set(names)) == 1 \
        else " + ".join(names)
    return Result(scene.name, device, estimator, width, height, spp, seconds,
                  width * height * spp / seconds / 1e6, rays / seconds / 1e6,
                  group.bvh_seconds, *builds, render_seconds=render_seconds,
                  render_rounds=times if rounds > 1 else None, mean=float(image.mean()),
                  path_queue=scene.settings.path_queue, path_sort=scene.settings.path_sort, queue_plan="; ".join(group.queue_plans()))


def kernel_build_times(backend, cold: bool = True):
    """Seconds to build the kernels of every feature without our binary cache (None unless `cold`:
    on NVIDIA's OpenCL that build tunes register caps, app/device/occupancy.py, a minute on the
    H100) and from it. Without `cold`, the second is None too where the cache does not hold
    them: filling it would be the very build that `cold` off skips."""
    device = backend.device.device
    if cold:
        cold = build_program(backend.context, device, use_cache=False).seconds
        build_program(backend.context, device)          # fills the cache if empty
    else:
        cold = None
        if not built_before(device, program_entry(device)):
            return None, None
    return cold, build_program(backend.context, device).seconds


def run(device_specs, scene_names, estimators, width, height, spp, together=False, cold=True,
        mitsuba: tuple = None, traversal: bool = False, split: bool = False, path_queue: int = 0,
        rounds: int = 1, divergence: int = 0, log=print, path_sort: bool = False):
    """A row per device and scene, or with `together` a row per scene for all the devices
    rendering it as one (the multi-device scaling measurement). mitsuba: (python, variant) to
    time Mitsuba 3 on the rows of the comparison mode with NEE (depth8+nee). path_queue: the
    render setting (pathtrace render --path-queue) for every row, and path_sort its --path-sort. rounds: the renders timed per
    row, pathtrace's and then Mitsuba's, whose medians count. divergence: the lanes of a warp with
    which to count each row's divergence (app/bench/divergence_stats.py); 0: none."""
    backends = choose_devices(device_specs)
    groups = [backends] if together else [[b] for b in backends]
    results = []
    folder = Path(tempfile.mkdtemp(prefix="pathtrace-bench-"))
    try:
        scenes = [scene_file(name, folder) for name in scene_names]
        for group in groups:
            builds = kernel_build_times(group[0], cold)
            for name in scenes:
                scene = load_scene(name).with_settings(path_queue=path_queue, path_sort=path_sort)
                for est in estimators or [default_estimator(scene)]:
                    r = measure(group, scene, est, width, height, spp, builds, rounds)
                    log(format_row(r))
                    if r.queue_plan:
                        log(f"  path queue auto: {r.queue_plan}")
                    if traversal:
                        count_traversal(r, group[0], scene)
                        log(format_traversal(r))
                    if split:
                        log(split_row(r, group[0], scene))
                    if divergence:
                        log(divergence_table(r, group[0], scene, divergence))
                    if mitsuba and est == "depth8+nee":
                        try:
                            twin = mitsuba_twin(scene, (r.width, r.height), r.spp, folder)
                        except UserError as e:     # the scene says what a twin cannot: no column
                            log(f"{'':<20} Mitsuba 3: no twin of {scene.name}: {e}")
                        else:
                            time_mitsuba(r, scene, twin, mitsuba, rounds)
                            log(format_mitsuba(r))
                    results.append(r)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return results


TRAVERSAL_SPP = 4       # samples per pixel of the counting renders: the ratios settle long before
SPLIT_SPP = 8           # of the trace split's renders (the first untimed)
DIVERGENCE_SPP = 4      # of the divergence stats' render


def count_traversal(r: Result, backend, scene):
    """The row's rays per sample and BVH work per ray (app/bench/traversal_stats.py), into r."""
    from pathtrace.bench.traversal_stats import traversal_stats
    stats = traversal_stats(backend, scene.with_settings(**estimator_settings(r.estimator)), r.width, r.height,
                            min(r.spp, TRAVERSAL_SPP))
    r.rays_per_sample, r.nodes_per_ray, r.primitives_per_ray = \
        stats.rays_per_sample, stats.nodes_per_ray, stats.primitives_per_ray


def divergence_table(r: Result, backend, scene, warp: int) -> str:
    """The row's divergence stats (app/bench/divergence_stats.py) into r, and their table; for a
    scene they do not follow, the line that says so."""
    from pathtrace.bench.divergence_stats import divergence_stats, format_stats
    try:
        r.divergence = divergence_stats(backend, scene.with_settings(**estimator_settings(r.estimator)), r.width,
                                        r.height, min(r.spp, DIVERGENCE_SPP), warp)
    except UserError as e:
        return f"{'':<20} {e}"
    return format_stats(r.divergence)


def split_row(r: Result, backend, scene) -> str:
    """The row's trace split (app/bench/trace_split.py) into r, and its line; for a scene the split's
    kernels do not follow, the line that says so."""
    from pathtrace.bench.trace_split import format_split, trace_split
    try:
        r.trace_split = trace_split(backend, scene, r.width, r.height, SPLIT_SPP)
    except UserError as e:
        return f"{'':<20} {e}"
    return format_split(r.trace_split)


def format_traversal(r: Result) -> str:
    return (f"{'':<20} traversal: {r.rays_per_sample:.2f} rays per sample, {r.nodes_per_ray:.1f} nodes "
            f"and {r.primitives_per_ray:.1f} primitives per ray")


def scene_file(name: str, folder: Path, size: tuple = None) -> str:
    """A scene name as load_scene takes it: one of GENERATED_FILES written into `folder`, with a
    film of `size` pixels where it is given (so that Mitsuba, which renders the file as it is,
    renders it at that size), else the file's own."""
    if name not in GENERATED_FILES:
        return name
    from pathtrace.bench.scenes import MATERIALS, write_obj_meshes, write_textured_tori
    where = folder / name
    where.mkdir(exist_ok=True)
    write = {"tori400-textured": write_textured_tori, "meshes850-obj": write_obj_meshes,
             "tori400-materials": partial(write_textured_tori, materials=MATERIALS)}[name]
    return str(write(where) if size is None else write(where, size=size))


def mitsuba_twin(scene, size: tuple, spp: int, folder: Path):
    """The Mitsuba 3 XML of a row's scene: its own file, or a twin written into `folder` with a
    film of `size` (width, height) and `spp` samples (UserError where the scene holds what a twin
    cannot say)."""
    from pathtrace.scene.mitsuba_writer import write_mitsuba
    source = str(scene.source or "")
    if source.lower().endswith(".xml"):
        return source
    twin = folder / f"{scene.name}-twin"
    twin.mkdir(exist_ok=True)
    return write_mitsuba(scene.with_settings(width=size[0], height=size[1], spp=spp, max_depth=COMPARISON_DEPTH),
                         twin / f"{scene.name}.xml")


def time_mitsuba(r: Result, scene, xml, mitsuba: tuple, rounds: int = 1):
    """Mitsuba 3's render of `xml`, the row's scene, into r: the median of `rounds` renders."""
    from pathtrace.bench.mitsuba_timing import mitsuba_render
    python, variant = mitsuba
    r.mitsuba_variant = variant
    times, r.mitsuba_mean = mitsuba_render(python, variant, xml, scene.camera, r.width, r.height, r.spp,
                                           COMPARISON_DEPTH, rounds)
    r.mitsuba_seconds = median(times)
    r.mitsuba_rounds = times if rounds > 1 else None


def format_mitsuba(r: Result) -> str:
    def timed(seconds, rounds):     # a median, with its rounds' range
        return f"{seconds:.3f} s" + (f" ({min(rounds):.3f}-{max(rounds):.3f})" if rounds else "")
    medians = f" (medians of {len(r.render_rounds)} renders)" if r.render_rounds else ""
    return (f"{'':<20} Mitsuba 3 {r.mitsuba_variant}: {timed(r.mitsuba_seconds, r.mitsuba_rounds)} to render; "
            f"pathtrace {timed(r.render_seconds, r.render_rounds)}: {r.mitsuba_seconds / r.render_seconds:.2f}x "
            f"per sample{medians} (image means {r.mean:.4f} and {r.mitsuba_mean:.4f})")


BUILD_SIZES = (64_000, 1_000_000, 4_000_000)


@dataclass
class BuildTime:
    scene: str
    device: str
    primitives: int
    seconds: float            # the median of three builds
    sah_cost: float           # pathtrace.compiler.bvh.BVH.cost
    nodes: int
    node_megabytes: float


def run_builds(device_specs, sizes, log=print):
    """A row per device, size and kind of primitive (spheres, triangles)."""
    import numpy as np

    from pathtrace.compiler.bvh import build_bvh, primitive_boxes
    from pathtrace.scene.builtin import count_name

    results = []
    for backend in choose_devices(device_specs):
        build_bvh(np.zeros((2, 3)), np.ones((2, 3)), queue=backend.queue)   # builds the kernel
        for n in sizes:
            for name in (f"spheres{count_name(n)}-diffuse", f"heightfield{count_name(n)}"):
                scene = load_scene(name)
                corners = np.concatenate([m.vertices[m.faces] for m in scene.meshes]) if scene.meshes \
                    else np.zeros((0, 3, 3), np.float32)
                lo, hi = primitive_boxes(scene.spheres, corners)
                seconds = []
                for _ in range(3):
                    start = time.perf_counter()
                    bvh = build_bvh(lo, hi, len(scene.spheres), backend.queue)
                    seconds.append(time.perf_counter() - start)
                r = BuildTime(name, backend.device.describe(), len(lo), sorted(seconds)[1], bvh.cost,
                              len(bvh.nodes), bvh.nodes.nbytes / 2**20)
                log(format_build_row(r))
                results.append(r)
    return results


@dataclass
class Timing:
    """One step of the viewer's frame or of denoising, timed on its own (the median of 30)."""
    what: str
    device: str
    width: int
    height: int
    milliseconds: float


def _median_ms(step, repeats: int = 30) -> float:
    step()                                # the first run allocates and builds
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        step()
        times.append(time.perf_counter() - start)
    return 1000 * sorted(times)[len(times) // 2]


def run_display(device_specs, width, height, log=print):
    """The image's way from the device to the host each frame, each of pathtrace.viewer.display's ways (the
    texture upload that follows is OpenGL's and is not timed here)."""
    from pathtrace.viewer.display import MODES, Display
    results = []
    for backend in choose_devices(device_specs):
        r = Renderer(backend, load_scene("simple"), width, height)
        r.add_samples(1)
        r.finish()
        default = Display(backend).mode
        for mode in MODES:
            display = Display(backend, mode)
            step = lambda: (display.request(r.buffer("sum"), width, height), display.wait(lambda p: None))  # noqa: E731
            chosen = " (default)" if mode == default else ""
            t = Timing(f"display: {mode}{chosen}", backend.device.describe(), width, height, _median_ms(step))
            log(format_timing(t))
            results.append(t)
    return results


def run_denoise(width, height, log=print):
    """Open Image Denoise on the demo's 4-sample image and guides, at each quality."""
    from pathtrace.io.denoiser import QUALITIES, Denoiser
    from pathtrace.device.opencl import choose_device
    r = Renderer(choose_device("auto"), load_scene("demo"), width, height)
    r.set_aovs(True)
    r.add_samples(4)
    image, aovs = r.mean(), r.read_aovs()
    albedo, normal = aovs["albedo"], aovs["normal"]
    results = []
    for quality in QUALITIES:
        with Denoiser(quality) as denoiser:
            t = Timing(f"denoise, {quality}", f"Open Image Denoise, {denoiser.device_name}", width, height,
                       _median_ms(lambda: denoiser(image, albedo, normal), repeats=5))
        log(format_timing(t))
        results.append(t)
    return results


TIMING_HEADER = f"{'step':<28} {'device':<44} {'size':>10} {'ms':>8}"


def format_timing(t: Timing) -> str:
    return f"{t.what:<28} {t.device[:44]:<44} {f'{t.width}x{t.height}':>10} {t.milliseconds:>8.2f}"


BUILD_HEADER = f"{'scene':<22} {'device':<44} {'primitives':>10} {'build s':>8} {'SAH cost':>9} {'nodes':>9} {'MB':>7}"


def format_build_row(r: BuildTime) -> str:
    return (f"{r.scene:<22} {r.device[:44]:<44} {r.primitives:>10} {r.seconds:>8.3f} {r.sah_cost:>9.2f} "
            f"{r.nodes:>9} {r.node_megabytes:>7.1f}")


HEADER = (f"{'scene':<20} {'device':<44} {'est.':<10} {'size':>9} {'spp':>5} {'seconds':>8} "
          f"{'Msamples/s':>10} {'Mrays/s':>8} {'BVH s':>6} {'build cold/warm s':>17}")


def format_row(r: Result) -> str:
    return (f"{r.scene:<20} {r.device[:44]:<44} {r.estimator:<10} {f'{r.width}x{r.height}':>9} "
            f"{r.spp:>5} {r.seconds:>8.3f} {r.msamples_per_s:>10.1f} {r.mrays_per_s:>8.1f} "
            f"{r.bvh_seconds:>6.3f} {'-' if r.build_cold_seconds is None else f'{r.build_cold_seconds:.2f}':>8}"
            f"/{'-' if r.build_warm_seconds is None else f'{r.build_warm_seconds:.3f}':<8}")


def write_json(path, results, argv):
    import pyopencl as cl
    data = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": "pathtrace " + " ".join(argv),
        "host": platform.node(), "python": sys.version.split()[0], "pyopencl": cl.VERSION_TEXT,
        "results": [asdict(r) for r in results],
    }
    from pathtrace.io.images import write_text
    write_text(path, json.dumps(data, indent=2) + "\n")


def validate(args):
    if args.quick:
        args.size, args.spp = args.size or (320, 180), args.spp or 8
    args.size = args.size or (1920, 1080)
    args.spp = args.spp or 1000
    args.scenes = args.scenes or list(TARGET_SCENES)
    for name in args.scenes:
        if name not in GENERATED_FILES:
            load_scene(name)     # fail on a bad name before any device work
    unknown = set(args.estimator or []) - set(ESTIMATORS)
    if unknown:
        raise UserError(f"--estimator: unknown '{sorted(unknown)[0]}' (use {', '.join(ESTIMATORS)})")
