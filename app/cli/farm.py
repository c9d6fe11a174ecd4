"""`pathtrace farm render`: stills or an orbit's frames rendered on a Ray cluster (app/rendering/farm.py)."""

import sys

from pathtrace.cli.interrupts import FinalWrite, check_interrupt
from pathtrace.cli.options import (SCENES_EPILOG, _finite, _int_range, add_output_options, add_render_options,
                                   apply_render_options)
from pathtrace.cli.progress import BuildProgress, redraw_interval
from pathtrace.errors import UserError, cut, short

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
    if args.orbit is not None and not args.frames:
        raise UserError("--orbit: the turn of the frames' orbit; give --frames N too")
    jobs = [farm.Job(i, scene.camera, scene.settings.spp) for i, scene in enumerate(scenes)]
    if args.frames:
        jobs = [farm.Job(0, camera, jobs[0].spp)
                for camera in farm.orbit(scenes[0].camera, args.frames, 360.0 if args.orbit is None else args.orbit)]
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
                   file=sys.stderr, disable=args.quiet, dynamic_ncols=True, mininterval=redraw_interval())
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


def add_parser(sub):
    """The `farm` command's parser, with its subcommand `render`."""
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
    p.add_argument("--orbit", type=_finite, metavar="DEGREES",
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
