"""`pathtrace render`: a still image of a scene, with its denoised form and its AOVs."""

import argparse
import os
import sys
from pathlib import Path

from pathtrace.cli.interrupts import FinalWrite, check_interrupt, interrupted, interrupted_status
from pathtrace.cli.options import SCENES_EPILOG, _int_range, add_output_options, add_render_options, apply_render_options
from pathtrace.cli.progress import BuildProgress, Phases, redraw_interval
from pathtrace.errors import UserError, escape, short

def cmd_render(args):
    from tqdm import tqdm

    from pathtrace import api
    from pathtrace.io.files import shown
    from pathtrace.io.images import HDR_FORMATS, check_writable, write_images

    written = {}
    for path in args.output:
        if "depth" in (args.aov or ()) and Path(path).suffix.lower() not in HDR_FORMATS:
            raise UserError(f"--aov depth: {short(str(path))}: a depth is a distance, not a colour; give an "
                            f"output of {', '.join(HDR_FORMATS)}")
        for target in [path, *(aov_path(path, name) for name in args.aov or ())]:
            check_writable(target)
            key = os.path.realpath(target)
            if key in written:
                raise UserError(f"--output: {short(str(target))} would be written twice "
                                f"(as {short(str(written[key]))} too)")
            written[key] = target
    phase = Phases(args.quiet)
    opening = api.DevicesOpening(args.device or ["auto"])     # while the scene is read
    denoiser = None
    if args.denoise:                 # before rendering: a missing or failing OIDN says so now
        from pathtrace.io.denoiser import Denoiser
        denoiser = Denoiser("high")
        phase(f"opened Open Image Denoise ({denoiser.device_name})")
    scene = apply_render_options(api.load(args.scene), args)
    phase(f"loaded {escape(scene.name)}")
    s = scene.settings
    pixels = s.width * s.height
    build_progress = BuildProgress(scene.name, args.quiet)
    bar, samples = None, 0         # the samples per pixel done (progress)
    said = False

    def say_devices():
        """The devices and their opening's time, once they are open: the scene compiles while
        they open (api.prepare), so this comes before or after its line."""
        nonlocal said
        if said:
            return
        said = True
        backends = opening.result()
        for backend in backends:
            print(f"device: {backend.device.describe()}", file=sys.stderr)
        generic = all(b.built_generic(media=False) is not None for b in backends)    # open_device's
        cached = "from the kernel cache, " if generic and all(b.opened.cached for b in backends) else ""
        phase(f"opened the device{'s' * (len(backends) > 1)}" + (" and built the generic kernels" if generic else ""),
              f" ({cached}beside the reading)", seconds=opening.seconds)

    def prepared(what, seconds):
        build_progress.close()       # a bar left open would share its line with this one
        if opening.opened():
            say_devices()
        phase(what, seconds=seconds)

    def progress(done):
        # made as the first samples start (after the BVH build): the rate and the time left from
        # the average since then (smoothing 0): the launches grow from one sample, so a smoothed
        # rate underestimates the time left; in samples per second always, as a fixed unit,
        # where tqdm would flip to seconds per sample
        nonlocal bar, samples
        samples = done               # the bar's own count stays 0 where -q disables it
        check_interrupt()
        if bar is None:
            build_progress.close()
            say_devices()
            bar = tqdm(total=s.spp, desc=f"{scene.name} {s.width}x{s.height}", file=sys.stderr,
                       disable=args.quiet, dynamic_ncols=True, smoothing=0, mininterval=redraw_interval(),
                       bar_format="{desc}: {percentage:3.0f}%|{bar}| {n}/{total} spp [{elapsed}<{remaining}{postfix}]")
        bar.update(done - bar.n)
        elapsed = bar.format_dict["elapsed"]
        if elapsed > 0:
            bar.set_postfix_str(f"{done * pixels / elapsed / 1e6:.2f} Msamples/s", refresh=False)
    try:
        result = api.render(scene, device=opening, progress=progress,
                            build_progress=build_progress, phases=prepared,
                            aovs=tuple(dict.fromkeys((*(("albedo", "normal") if args.denoise else ()),
                                                      *(args.aov or ())))))
    except (UserError, KeyboardInterrupt) as e:
        if isinstance(e, UserError) and not interrupted():   # the scene does not fit, or its kernels fail
            if opening.opened():
                say_devices()
            raise
        done = samples
        # the bars closed first (each ends its line), so that the message starts a line of its own
        build_progress.close()
        if bar is not None:
            bar.close()
        print(f"pathtrace: interrupted at {done}/{s.spp} spp; nothing written", file=sys.stderr)
        return interrupted_status()
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


AOVS = ("albedo", "normal", "depth")


def _aovs(text: str) -> tuple:
    names = tuple(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))   # each once
    unknown = [n for n in names if n not in AOVS]
    if unknown or not names:
        raise argparse.ArgumentTypeError(f"{short(text)}: give albedo, normal, depth or a list (albedo,normal)")
    return names


def aov_path(path: str, name: str) -> Path:
    """Where --aov writes `name` beside an output: out.png -> out.albedo.png."""
    path = Path(path)
    return path.with_name(f"{path.stem}.{name}{path.suffix}")


def render_outputs(result, args, denoiser=None) -> list:
    """What `render` writes from api.render's result: the image (denoised by `denoiser` with
    --denoise; an EXR then keeps the noisy one as its layer "noisy") to every --output, and with
    --aov the albedo, normal and depth beside each (normals stored as n / 2 + 1/2 in PNG and
    JPEG, the usual encoding; the depth, the distance from the camera to the first surface and 0
    where the camera ray escaped, in each channel of an HDR file)."""
    import numpy as np

    from pathtrace.io.images import HDR_FORMATS, Output
    noisy = result["image"] if isinstance(result, dict) else result
    image, layers = noisy, {}
    aovs = result if isinstance(result, dict) else {}
    if denoiser is not None:
        image, layers = denoiser(noisy, aovs["albedo"], aovs["normal"]), {"noisy": noisy}
    outputs = []
    for path in args.output:
        suffix = Path(path).suffix.lower()
        hdr = suffix in HDR_FORMATS
        outputs.append(Output(Path(path), image, layers if suffix == ".exr" else {}))
        for name in args.aov or ():
            aov = aovs[name] if name != "depth" else np.repeat(aovs[name][..., None], 3, -1)
            aov = aov * 0.5 + 0.5 if name == "normal" and not hdr else aov
            outputs.append(Output(aov_path(path, name), aov, raw=True))
    return outputs


def add_parser(sub):
    """The `render` command's parser."""
    p = sub.add_parser("render", help="render a still image", epilog=SCENES_EPILOG)
    p.add_argument("scene", help="a .toml, Mitsuba 3 .xml or pbrt-v4 .pbrt scene file, or a built-in scene name")
    p.add_argument("-o", "--output", action="append", required=True, metavar="FILE",
                   help="output image; repeat for several (.png/.jpg tonemapped; "
                        ".exr/.hdr/.pfm linear HDR)")
    p.add_argument("--spp", type=_int_range(1, 2**31 - 1), help="samples per pixel (default: the scene's)")
    p.add_argument("--denoise", action="store_true",
                   help="denoise with Intel Open Image Denoise, guided by the albedo and normal "
                        "(an .exr output keeps the noisy image as its layer 'noisy')")
    p.add_argument("--aov", type=_aovs, metavar="albedo,normal,depth",
                   help="also write the denoiser's albedo and normal, or the depth (HDR outputs only), beside "
                        "each output (out.png -> out.albedo.png, out.normal.png; out.exr -> out.depth.exr)")
    add_output_options(p)
    add_render_options(p)
    p.set_defaults(func=cmd_render)
