"""pathtrace: an interactive, progressive path tracer with OpenCL kernels."""

import argparse
import contextlib
import os
import signal
import sys
import time
from dataclasses import replace
from pathlib import Path

from pathtrace import __version__
from pathtrace.console import INTERRUPTED, check_interrupt
from pathtrace.errors import UserError, cut, did_you_mean, escape, short, warn
from pathtrace.lights import LIGHT_SAMPLERS
from pathtrace.scene.description import INTEGRATORS, MAX_PATH_QUEUE, PATH_QUEUE_AUTO, RUSSIAN_ROULETTE

GENERATED_SCENES = (("spheresN[-diffuse]", "N random spheres, e.g. spheres512k, spheres1M-diffuse"),
                    ("heightfieldN", "a height field of about N triangles, e.g. heightfield1M"))


def epilog() -> str:
    from pathtrace.scene.builtin import BUILTIN_SCENES
    return ("A scene is a .toml file, a Mitsuba 3 .xml file, a pbrt-v4 .pbrt file or a built-in name (pathtrace scenes lists them): "
            + ", ".join(BUILTIN_SCENES) + "; and " + ", ".join(name for name, _ in GENERATED_SCENES) + ".")


PROGRESS_AFTER = 1.0    # seconds before a BVH build shows its progress


class FinalWrite:
    """Around the writing of a command's outputs (all or none, app/io/images.py): Ctrl-C and
    SIGTERM wait until it ends, and once the outputs are complete they are ignored, so that a
    signal arriving then cannot turn a finished command into an 'interrupted' exit (130). A
    write that fails restores the handlers, and a signal received meanwhile then interrupts."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __enter__(self):
        # Python's handlers, which run in the main thread whichever thread the signal reached
        # (masking the signal would hold it in this thread only, not in the OpenCL driver's)
        self.received = None
        self.saved = {s: signal.signal(s, self._defer) for s in self.SIGNALS}
        return self

    def _defer(self, signum, frame):
        self.received = signum

    def __exit__(self, kind, *exc):
        if kind is None:                 # complete: a signal now changes nothing
            for s in self.SIGNALS:
                signal.signal(s, signal.SIG_IGN)
            return
        for s, handler in self.saved.items():
            signal.signal(s, handler)
        if self.received is not None and kind is not KeyboardInterrupt:
            raise KeyboardInterrupt


class BuildProgress:
    """A progress bar for a scene's BVH build on standard error, shown once the build has taken
    PROGRESS_AFTER seconds; call it with the fraction done."""

    def __init__(self, name: str, quiet: bool):
        from tqdm import tqdm
        self.bar = tqdm(total=100, desc=f"{name}: building the BVH", unit="%", delay=PROGRESS_AFTER,
                        file=sys.stderr, disable=quiet, bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}")

    def __call__(self, fraction: float):
        self.bar.update(100 * fraction - self.bar.n)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        self.bar.close()


class Phases:
    """The lines of `render`'s phases on standard error, each with its time: called with what
    was done as each phase ends, it prints "WHAT in SECONDS s" (nothing when quiet). A phase's
    time runs from the end of the one before (or from restart()); one timed elsewhere gives its
    `seconds`."""

    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.restart()

    def restart(self):
        """Times the next phase from now."""
        self.start = time.perf_counter()

    def __call__(self, what: str, note: str = "", seconds: float = None):
        if seconds is None:
            seconds = time.perf_counter() - self.start
        if not self.quiet:
            print(f"{what} in {seconds:.2f} s{note}", file=sys.stderr)
        self.restart()


def _size(text):
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
    from pathtrace.io.tonecurve import TONEMAPS
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
                        "scene's own: repeatable renders) or generic (never build another); default "
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
    p.add_argument("--size", type=_size, metavar="WxH", help="image size (default: the scene's)")
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


def _path_queue(text: str) -> int:
    if text == "auto":
        return PATH_QUEUE_AUTO
    try:
        return _int_range(0, MAX_PATH_QUEUE)(text)
    except argparse.ArgumentTypeError as e:
        raise argparse.ArgumentTypeError(f"{e}; or auto") from None


def _pixel_filter(text: str):
    from pathtrace.filters import PixelFilter
    name, *numbers = text.split(":")
    try:
        values = [float(x) for x in numbers]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{short(text)}: radius and stddev must be numbers") from None
    if len(values) > (2 if name == "gaussian" else 1):
        raise argparse.ArgumentTypeError(f"{short(text)}: too many numbers for a {short(name)} filter")
    try:
        return PixelFilter(name, *values).check()
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


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
                   integrator=getattr(args, "integrator", None) or s.integrator)
    if not replace(s, **changes).paths_end:
        raise UserError("--rr off needs --max-depth N (N >= 1), or paths would never end")
    if not changes["nee"] and scene.lights:
        warn(f"{scene.name}: its {len(scene.lights)} point, spot or directional light(s) are reached by "
             f"next-event estimation only; without it (--no-nee) they light nothing")
    if getattr(args, "spp", None) is not None:
        changes["spp"] = args.spp
    return scene.with_settings(**changes)


def cmd_devices(args):
    from pathtrace.device.opencl import NO_DEVICE, build_error_line, list_devices, open_device
    from pathtrace.device.programs import warm_up
    import pyopencl as cl

    devices = list_devices()
    if not devices:
        raise UserError(NO_DEVICE)
    for d in devices:
        line = f"[{d.index}] {d.describe()}, {d.device.max_compute_units} compute units"
        if args.check:
            try:
                b = open_device(d, mode="generic")
                start = time.perf_counter()
                cached = b.built_generic() is not None and b.opened.cached
                b.program
                line += (f": builds the generic kernels ({time.perf_counter() - start + b.opened.seconds:.2f} s"
                         f"{', cached' if cached else ''}) and renders with them ({warm_up(b):.2f} s)")
            except cl.Error as e:
                line += f": cannot build the kernels: {build_error_line(e)}"
        print(line)
    return 0


def cmd_scenes(args):
    from pathtrace.scene.builtin import BUILTIN_SCENES
    for name in BUILTIN_SCENES:
        print(name)
    for name, what in GENERATED_SCENES:
        print(f"{name}: {what}")
    return 0


def cmd_render(args):
    from tqdm import tqdm

    from pathtrace import api
    from pathtrace.io.files import shown
    from pathtrace.io.images import check_writable, write_images

    written = {}
    for path in args.output:
        for target in [path, *(aov_path(path, name) for name in args.aov or ())]:
            check_writable(target)
            key = os.path.realpath(target)
            if key in written:
                raise UserError(f"--output: {short(str(target))} would be written twice "
                                f"(as {short(str(written[key]))} too)")
            written[key] = target
    phase = Phases(args.quiet)
    denoiser = None
    if args.denoise:                 # before rendering: a missing or failing OIDN says so now
        from pathtrace.io.denoiser import Denoiser
        denoiser = Denoiser("high")
        phase(f"opened Open Image Denoise ({denoiser.device_name})")
    scene = apply_render_options(api.load(args.scene), args)
    phase(f"loaded {escape(scene.name)}")
    s = scene.settings
    backends = api.open_devices(args.device or ["auto"])
    for backend in backends:
        print(f"device: {backend.device.describe()}", file=sys.stderr)
    generic = all(b.built_generic() is not None for b in backends)
    cached = " (from the kernel cache)" if generic and all(b.opened.cached for b in backends) else ""
    phase(f"opened the device{'s' * (len(backends) > 1)}" + (" and built the generic kernels" if generic else ""),
          cached)
    pixels = s.width * s.height
    build_progress = BuildProgress(scene.name, args.quiet)
    bar = None

    def prepared(what, seconds):
        build_progress.close()       # a bar left open would share its line with this one
        phase(what, seconds=seconds)

    def progress(done):
        # made as the first samples start (after the BVH build): the rate and the time left from
        # the average since then (smoothing 0): the launches grow from one sample, so a smoothed
        # rate underestimates the time left; in samples per second always, as a fixed unit,
        # where tqdm would flip to seconds per sample
        nonlocal bar
        check_interrupt()
        if bar is None:
            build_progress.close()
            bar = tqdm(total=s.spp, desc=f"{scene.name} {s.width}x{s.height}", file=sys.stderr,
                       disable=args.quiet, dynamic_ncols=True, smoothing=0,
                       bar_format="{desc}: {percentage:3.0f}%|{bar}| {n}/{total} spp [{elapsed}<{remaining}{postfix}]")
        bar.update(done - bar.n)
        elapsed = bar.format_dict["elapsed"]
        if elapsed > 0:
            bar.set_postfix_str(f"{done * pixels / elapsed / 1e6:.2f} Msamples/s", refresh=False)
    try:
        result = api.render(scene, device=args.device or ["auto"], progress=progress,
                            build_progress=build_progress, phases=prepared,
                            aovs=("albedo", "normal") if args.denoise or args.aov else ())
    except KeyboardInterrupt:
        done = 0 if bar is None else bar.n
        # the bars closed first (each ends its line), so that the message starts a line of its own
        build_progress.close()
        if bar is not None:
            bar.close()
        print(f"pathtrace: interrupted at {done}/{s.spp} spp; nothing written", file=sys.stderr)
        return INTERRUPTED
    finally:
        build_progress.close()
        if bar is not None:
            bar.close()
    for plan in api.queue_plans(scene):
        print(f"path queue auto: {plan}", file=sys.stderr)
    if not args.quiet:
        for words in api.programs_used(scene):
            print(words, file=sys.stderr)
    phase.restart()                  # from the end of the render
    outputs = render_outputs(result, args, denoiser)
    if denoiser is not None:
        phase("denoised")
    with FinalWrite():
        write_images(outputs, args.exposure, args.tonemap)
    if args.quiet:
        for out in outputs:
            print(f"wrote {shown(out.path)}", file=sys.stderr)
    else:
        phase("wrote " + ", ".join(shown(out.path) for out in outputs))
    return 0


AOVS = ("albedo", "normal")


def _aovs(text: str) -> tuple:
    names = tuple(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))   # each once
    unknown = [n for n in names if n not in AOVS]
    if unknown or not names:
        raise argparse.ArgumentTypeError(f"{short(text)}: give albedo, normal or albedo,normal")
    return names


def aov_path(path: str, name: str) -> Path:
    """Where --aov writes `name` beside an output: out.png -> out.albedo.png."""
    path = Path(path)
    return path.with_name(f"{path.stem}.{name}{path.suffix}")


def render_outputs(result, args, denoiser=None) -> list:
    """What `render` writes from api.render's result: the image (denoised by `denoiser` with
    --denoise; an EXR then keeps the noisy one as its layer "noisy") to every --output, and with
    --aov the albedo and normal beside each (normals stored as n / 2 + 1/2 in PNG and JPEG, the
    usual encoding)."""
    from pathtrace.io.images import HDR_FORMATS, Output
    noisy = result["image"] if isinstance(result, dict) else result
    image, layers = noisy, {}
    if isinstance(result, dict):
        albedo, normal = result["albedo"], result["normal"]
    if denoiser is not None:
        image, layers = denoiser(noisy, albedo, normal), {"noisy": noisy}
    outputs = []
    for path in args.output:
        suffix = Path(path).suffix.lower()
        hdr = suffix in HDR_FORMATS
        outputs.append(Output(Path(path), image, layers if suffix == ".exr" else {}))
        for name in args.aov or ():
            aov = albedo if name == "albedo" else (normal if hdr else normal * 0.5 + 0.5)
            outputs.append(Output(aov_path(path, name), aov, raw=True))
    return outputs


def cmd_convert(args):
    """All or nothing: the TOML and its side files (NAME.environment.exr, NAME.meshes/) are
    checked, then written under temporary names and renamed into place together, so that a
    failure (a read-only folder, a full disk, a FIFO where a file goes) leaves none of them."""
    from pathtrace.api import load
    from pathtrace.io.images import Staged, _write_exr, check_writable
    from pathtrace.scene.toml_writer import scene_toml

    out = Path(args.output)
    if out.suffix.lower() != ".toml":
        raise UserError(f"--output: {out}: pathtrace writes scenes as .toml")
    scene = load(args.scene)
    check_writable(out, "--output", formats=None)
    env = scene.environment
    map_path = out.with_name(out.stem + ".environment.exr") if env.resampled else None
    if map_path:             # the map as pathtrace reads it, beside the scene
        check_writable(map_path, "--output", formats=(".exr",))
    meshes = mesh_files(scene, out)
    folder = out.with_name(out.stem + ".meshes")
    if meshes and os.path.lexists(folder) and not folder.is_dir():
        raise UserError(f"--output: '{folder}' exists and is not a folder, where the meshes go")
    made_folder = bool(meshes) and not folder.exists()
    try:
        with Staged() as staged:
            if made_folder:
                folder.mkdir()
            for path, _ in meshes:
                check_writable(path, "--output", formats=None)
            if map_path:
                staged.add(map_path, lambda tmp: _write_exr(tmp, env.image), "--output")
                scene.environment = replace(env, source=str(map_path), resampled=False)
            for path, mesh in meshes:
                staged.add(path, lambda tmp, m=mesh: write_mesh_file(tmp, m), "--output")
            text = scene_toml(scene, out)
            staged.add(out, lambda tmp: write_text_file(tmp, text), "--output")
            with FinalWrite():
                staged.commit()
    except BaseException:
        if made_folder:
            with contextlib.suppress(OSError):
                folder.rmdir()       # empty: its files were only staged
        raise
    if map_path:
        print(f"wrote {map_path}", file=sys.stderr)
    if meshes:
        print(f"wrote {len(meshes)} meshes to {out.stem}.meshes/", file=sys.stderr)
    print(f"wrote {out}", file=sys.stderr)
    return 0


def mesh_files(scene, out: Path, inline_faces: int = 1000) -> list:
    """(path, mesh) of the meshes that came from no file (a pbrt scene's, whose faces and uvs
    the reader turned), to be written as PLY files beside the TOML where they have normals (an
    inline mesh has none) or more than `inline_faces` faces; each mesh is set to refer to its
    file, as the TOML will."""
    import numpy as np

    from pathtrace.scene.description import MeshFile

    folder = out.with_name(out.stem + ".meshes")
    found = []
    objects = scene.instances.objects if scene.instances is not None else []
    for k, mesh in enumerate(scene.meshes + [m for o in objects for m in o.meshes]):
        if mesh.file is not None or (mesh.normals is None and len(mesh.faces) <= inline_faces):
            continue
        path = folder / f"{k:04d}.ply"
        found.append((path, mesh))
        mesh.file = MeshFile(str(path), np.eye(4))
    return found


def write_text_file(path, text: str) -> bool:
    Path(path).write_text(text)
    return True


def write_mesh_file(path, mesh) -> bool:
    from pathtrace.scene.meshes import write_ply
    write_ply(path, mesh.vertices, mesh.faces, mesh.normals, mesh.uvs)
    return True


def cmd_farm_render(args):
    import time

    import numpy as np
    from tqdm import tqdm

    from pathtrace.rendering import farm
    from pathtrace.compiler.compiled import compile_scene
    from pathtrace.io.files import shown
    from pathtrace.io.images import Output, check_writable, write_images
    from pathtrace.scene import load_scene

    scenes = [apply_render_options(load_scene(name), args) for name in args.scene]
    if args.frames and len(scenes) > 1:
        raise UserError("--frames: give one scene, whose camera the frames orbit")
    jobs = [farm.Job(i, scene.camera, scene.settings.spp) for i, scene in enumerate(scenes)]
    if args.frames:
        jobs = [farm.Job(0, camera, jobs[0].spp) for camera in farm.orbit(scenes[0].camera, args.frames, args.orbit)]
    for k, job in enumerate(jobs):
        job.output = farm_output(args.output, scenes[job.scene].name, k, len(jobs))
        check_writable(job.output)
    if len({job.output for job in jobs}) < len(jobs):
        raise UserError(f"--output {args.output}: several images would share a name; put "
                        "{name} (the scene's) or {frame} (its number) in it")
    compiled = []
    for scene in scenes:
        with BuildProgress(scene.name, args.quiet) as progress:
            compiled.append(compile_scene(scene, progress=progress))
    ray = farm.connect(args.address, args.num_cpus, args.num_gpus)
    try:
        actors = farm.start_actors(ray, compiled, args.cpu_actors)
        for _, device in actors:
            print(f"worker: {device}", file=sys.stderr)
        total = sum(job.spp for job in jobs)
        bar = tqdm(total=total, unit="spp", desc=f"farm: {len(jobs)} image{'s' * (len(jobs) > 1)}",
                   file=sys.stderr, disable=args.quiet, dynamic_ncols=True)
        start = time.perf_counter()
        renders = farm.Farm(ray, actors, compiled)

        def on_batch(count):
            check_interrupt()
            bar.update(count)
        try:
            sums, _ = renders.render(jobs, on_batch)
        finally:
            bar.close()
        lost = renders.lost_workers
        print(f"farm: {total} spp in {time.perf_counter() - start:.2f} s on {len(actors)} "
              f"worker{'s' * (len(actors) > 1)}"
              + (f" ({lost} died; the others rendered its samples)" if lost == 1 else
                 f" ({lost} died; the others rendered their samples)" if lost else ""), file=sys.stderr)
    finally:
        ray.shutdown()
    # all or none, as every command writes: a failure at the last frame leaves no earlier one
    outputs = [Output(job.output, (total_sum[..., :3] / job.spp).astype(np.float32))
               for job, total_sum in zip(jobs, sums)]
    with FinalWrite():
        write_images(outputs, args.exposure, args.tonemap)
    for out in outputs:
        print(f"wrote {shown(out.path)}", file=sys.stderr)
    return 0


def farm_output(pattern: str, name: str, frame: int, count: int) -> str:
    """The output file of image `frame` of `count`: `pattern` with {name} and {frame} filled
    in (a pattern for one image may have neither)."""
    try:
        return pattern.format(name=name, frame=frame)
    except (KeyError, IndexError, ValueError, AttributeError, TypeError) as e:   # '{name.x}'
        raise UserError(f"--output {short(pattern)}: only {{name}} and {{frame}} may stand in braces "
                        f"({type(e).__name__}: {cut(str(e))})") from None


def cmd_view(args):
    from pathtrace import api

    if args.device and len(args.device) > 1:
        raise UserError("--device: the viewer renders on one device; give one (several are "
                        "for 'pathtrace render')")
    from pathtrace.viewer.window import require_display
    require_display()      # before any device work
    api.view(lambda: apply_render_options(api.load(args.scene), args), (args.device or ["auto"])[0],
             frames=args.frames, screenshot_dir=args.screenshot_dir, screenshot=args.screenshot)
    return 0


def cmd_bench(args):
    from pathtrace.bench import report as bench

    timing_size = args.size or ((320, 180) if args.quick else (1280, 720))
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
                                                args.mitsuba_variant)]
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
    print(bench.HEADER)
    results = bench.run(args.device or ["auto"], args.scenes, args.estimator, width, height, args.spp,
                        args.together, not args.no_cold,
                        (args.mitsuba, args.mitsuba_variant) if args.mitsuba else None, args.traversal,
                        args.trace_split, args.path_queue or 0, args.rounds)
    if args.json:
        bench.write_json(args.json, results, sys.argv[1:])
        print(f"wrote {args.json}", file=sys.stderr)
    return 0


# The epilog of the commands that take a scene, written out only when help is shown: the names
# of the built-in scenes come from their module, which no other command need import
SCENES_EPILOG = "(the scenes)"


def build_parser():
    parser = Parser(prog="pathtrace", description=__doc__, epilog=SCENES_EPILOG)
    parser.add_argument("--version", action="version", version=f"pathtrace {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("render", help="render a still image", epilog=SCENES_EPILOG)
    p.add_argument("scene", help="a .toml, Mitsuba 3 .xml or pbrt-v4 .pbrt scene file, or a built-in scene name")
    p.add_argument("-o", "--output", action="append", required=True, metavar="FILE",
                   help="output image; repeat for several (.png/.jpg tonemapped; "
                        ".exr/.hdr/.pfm linear HDR)")
    p.add_argument("--spp", type=_int_range(1, 2**31 - 1), help="samples per pixel (default: the scene's)")
    p.add_argument("--denoise", action="store_true",
                   help="denoise with Intel Open Image Denoise, guided by the albedo and normal "
                        "(an .exr output keeps the noisy image as its layer 'noisy')")
    p.add_argument("--aov", type=_aovs, metavar="albedo,normal",
                   help="also write the denoiser's albedo and/or normal beside each output "
                        "(out.png -> out.albedo.png, out.normal.png)")
    add_output_options(p)
    add_render_options(p)
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("view", help="open the interactive viewer", epilog=SCENES_EPILOG)
    p.add_argument("scene", nargs="?", default="simple",
                   help="a .toml, Mitsuba 3 .xml or pbrt-v4 .pbrt file, or a built-in name (default simple)")
    p.add_argument("--screenshot-dir", default="screenshots", metavar="DIR",
                   help="where P / F12 / the panel's button write PNG + EXR (default ./screenshots)")
    p.add_argument("--frames", type=_int_range(1), metavar="N", help="close after N frames (for scripts)")
    p.add_argument("--screenshot", action="store_true", help="take a screenshot when closing")
    add_render_options(p, queue_auto=False)     # no trial renders in the viewer: its panel sets N
    p.set_defaults(func=cmd_view)

    from pathtrace.bench.report import FIRST_IMAGE_SCENES, TARGET_SCENES
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
                   help="built-in names or scene files (default: " + " ".join(TARGET_SCENES) + "; with "
                        "--first-image: " + " ".join(FIRST_IMAGE_SCENES) + ")")
    p.add_argument("--estimator", action="append", metavar="EST",
                   help="rr (the report's), depth8 (comparison mode), or either with +nee "
                        "(next-event estimation); repeatable; default: rr for the report's "
                        "scenes, depth8 for -diffuse ones, both without NEE")
    p.add_argument("--size", type=_size, metavar="WxH", help="default 1920x1080 (with --first-image 640x360)")
    p.add_argument("--spp", type=_int_range(1, 2**31 - 1), help="samples per pixel (default 1000)")
    p.add_argument("--together", action="store_true",
                   help="render each scene on all the --device devices at once (one row per "
                        "scene) instead of on each in turn")
    p.add_argument("--builds", nargs="*", type=_count, metavar="N",
                   help="time BVH builds instead of renders: random spheres and a height field of "
                        "N primitives each (a k or M suffix allowed; default 64k 1M 4M)")
    p.add_argument("--display", action="store_true",
                   help="time the viewer's copy of the image to the host each frame (default size 1280x720)")
    p.add_argument("--denoise", action="store_true",
                   help="time Open Image Denoise at each quality (default size 1280x720)")
    p.add_argument("--no-cold", action="store_true",
                   help="skip timing the kernels' build without the cache (on NVIDIA's OpenCL it tunes "
                        "register caps, about a minute)")
    p.add_argument("--traversal", action="store_true",
                   help="also count, for each row, the rays per sample and the BVH nodes visited and "
                        "primitives tested per ray (three renders of 4 spp at the row's size)")
    p.add_argument("--trace-split", action="store_true",
                   help="also time, for each row, its depth-2 paths against the same rays traced by a "
                        "kernel that only walks the BVH: how much of the time is tracing (8 spp at the "
                        "row's size)")
    p.add_argument("--load", action="store_true",
                   help="time loading instead: seconds from 'pathtrace render FILE' to its first image "
                        "(1 spp) for a 1M-triangle PLY file and for 850 PLY meshes in a pbrt-v4 file")
    p.add_argument("--first-image", action="store_true",
                   help="time the first image instead: seconds from 'pathtrace render SCENE --spp 1' "
                        "to its image written, in fresh processes, cold (every kernel and BVH cache "
                        "empty) and warm (the caches the cold run filled), for --scenes and --load-scene")
    p.add_argument("--load-scene", action="append", metavar="FILE",
                   help="with --load or --first-image, also time this scene file (repeatable)")
    p.add_argument("--repeats", type=_int_range(1, 100), default=3,
                   help="with --load or --first-image, the best of this many runs (default 3)")
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

    p = sub.add_parser("farm", help="render on a Ray cluster (docs/farm.md)", epilog=SCENES_EPILOG)
    farm_sub = p.add_subparsers(dest="farm_command", required=True, metavar="COMMAND")
    p = farm_sub.add_parser("render", help="render stills, or the frames of an orbit, on every "
                                           "device of a Ray cluster", epilog=SCENES_EPILOG)
    p.add_argument("scene", nargs="+", help="scene files or built-in names: one image each")
    p.add_argument("-o", "--output", required=True, metavar="FILE",
                   help="output image; with several images, put {name} (the scene's name) or "
                        "{frame} (the image's number) in it, as in 'out/{name}-{frame:03d}.exr'")
    p.add_argument("--spp", type=_int_range(1, 2**31 - 1), help="samples per pixel (default: the scene's)")
    p.add_argument("--frames", type=_int_range(1), metavar="N",
                   help="render N frames of the camera orbiting its look-at point")
    p.add_argument("--orbit", type=_finite, default=360.0, metavar="DEGREES",
                   help="how far the --frames orbit turns (default 360)")
    p.add_argument("--address", metavar="ADDR",
                   help="the Ray cluster to join ('auto': the one 'ray start' began on this "
                        "machine, or host:port); default: start a local one")
    p.add_argument("--num-cpus", type=_int_range(1), metavar="N",
                   help="CPUs of the local cluster started without --address (default: all)")
    p.add_argument("--num-gpus", type=_int_range(0), metavar="N",
                   help="GPUs of the local cluster started without --address (default: all)")
    p.add_argument("--cpu-actors", type=_int_range(0), metavar="N",
                   help="workers rendering with PoCL on CPUs (default: 1 if the cluster has no "
                        "GPU, else 0); one actor per GPU is always started")
    add_output_options(p)
    add_render_options(p, device=False)
    p.set_defaults(func=cmd_farm_render)

    p = sub.add_parser("convert", help="write a scene (a Mitsuba 3 .xml or pbrt-v4 .pbrt file, say) as pathtrace TOML",
                       epilog=SCENES_EPILOG)
    p.add_argument("scene", help="a .xml, .pbrt or .toml scene file or a built-in scene name")
    p.add_argument("-o", "--output", required=True, metavar="FILE.toml",
                   help="the TOML file to write (mesh files stay where they are, referenced)")
    p.set_defaults(func=cmd_convert)

    p = sub.add_parser("devices", help="list OpenCL platforms and devices")
    p.add_argument("--check", action="store_true", help="also build the generic kernels on each and render with them once, which fills the drivers' caches (pathtrace.device.programs)")
    p.set_defaults(func=cmd_devices)

    p = sub.add_parser("scenes", help="list the built-in scenes")
    p.set_defaults(func=cmd_scenes)
    return parser


class Parser(argparse.ArgumentParser):
    """argparse's parser, whose messages echo what the user typed cut short: argparse quotes an
    invalid choice or an unknown option whole, however long, and an ambiguous one raw."""

    MESSAGE_LIMIT = 400

    def format_help(self):
        if self.epilog == SCENES_EPILOG:
            self.epilog = epilog()
        return super().format_help()

    def error(self, message):
        super().error(cut(" ".join(cut(word) for word in message.split(" ")), self.MESSAGE_LIMIT)
                      + self.suggestion(message))

    def suggestion(self, message: str) -> str:
        """"; did you mean ...?" for an unknown option (among this parser's) or an invalid
        choice (among the argument's), where one is close to what was typed."""
        import re
        choice = re.match(r"argument (\S+): invalid choice: '(.*)' \(choose from (.*)\)$", message)
        if choice:
            return did_you_mean(choice[2], re.findall(r"'([^']*)'", choice[3]))
        unknown = re.match(r"unrecognized arguments: (.*)$", message)
        options = [o for a in self._actions for o in a.option_strings if o.startswith("--")]
        for word in unknown[1].split(" ") if unknown else ():
            if word.startswith("--"):
                return did_you_mean(word.split("=")[0], options)
        return ""


def parse(parser: argparse.ArgumentParser, argv):
    """parse_args, except that an unknown option is reported with the usage of the subcommand it
    was given to, not the top level's."""
    args, extra = parser.parse_known_args(argv)
    if extra:
        chosen = parser
        for dest in ("command", "farm_command"):   # down the chain of subcommands
            action = next((a for a in chosen._actions if isinstance(a, argparse._SubParsersAction)), None)
            if action is None or getattr(args, dest, None) is None:
                break
            chosen = action.choices[getattr(args, dest)]
        chosen.error(f"unrecognized arguments: {' '.join(extra)}")
    return args


def choose_program_mode(args):
    """--program, for every device this process opens and the renders it starts
    (pathtrace.device.programs). bench times the scenes' own programs' renders unless asked otherwise;
    its --load and --first-image time commands as a user runs them."""
    from pathtrace.device.programs import PROGRAM_ENV
    times_renders = args.command == "bench" and not (args.load or args.first_image)
    mode = getattr(args, "program", None) or (
        "specialised" if times_renders and not os.environ.get(PROGRAM_ENV) else None)
    if mode:
        os.environ[PROGRAM_ENV] = mode


def main(argv=None) -> int:
    """Runs one command; returns its exit status (pathtrace.console: the entry point around it)."""
    args = parse(build_parser(), argv)
    try:
        choose_program_mode(args)
        if sys.stdout is None:          # started with standard output closed (>&-)
            if args.command in ("scenes", "devices", "bench"):
                raise UserError("cannot write the standard output: it is closed")
            sys.stdout = open(os.devnull, "w")
        code = args.func(args)
        sys.stdout.flush()
        return code
    except UserError as e:
        print(f"pathtrace: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("pathtrace: interrupted", file=sys.stderr)
        return INTERRUPTED
    except MemoryError:
        print("pathtrace: error: out of memory (a smaller --size, fewer samples at once or a smaller "
              "scene may fit)", file=sys.stderr)
        return 1
    except OSError as e:
        if e.filename is not None:
            raise                       # not standard output: a fault of ours, shown as such
        sys.stdout = open(os.devnull, "w")   # so that the exit does not try the flush again
        print(f"pathtrace: error: cannot write the standard output ({e.strerror})", file=sys.stderr)
        return 1

