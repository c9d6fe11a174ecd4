"""`pathtrace devices` and `pathtrace scenes`: what this machine and pathtrace offer."""

import time

from pathtrace.errors import UserError

GENERATED_SCENES = (("spheresN[-diffuse]", "N random spheres, e.g. spheres512k, spheres1M-diffuse"),
                    ("heightfieldN", "a height field of about N triangles, e.g. heightfield1M"))


def epilog() -> str:
    from pathtrace.scene.builtin import BUILTIN_SCENES
    return ("A scene is a .toml file, a Mitsuba 3 .xml file, a pbrt-v4 .pbrt file or a built-in name (pathtrace scenes lists them): "
            + ", ".join(BUILTIN_SCENES) + "; and " + ", ".join(name for name, _ in GENERATED_SCENES) + ".")


def cmd_devices(args):
    from pathtrace.device.opencl import build_error_line, generic_refused, list_devices, no_device, open_device
    import pyopencl as cl

    devices = list_devices()
    if not devices:
        raise UserError(no_device())
    building = 0        # the devices checked that build the kernels
    for d in devices:
        line = f"[{d.index}] {d.describe()}, {d.device.max_compute_units} compute units"
        b, builds = None, False         # whether its compiler built kernels here
        if args.check and generic_refused(d.device):
            line += (": its generic kernels rendered wrongly at an earlier check (a mark in the kernel cache, "
                     "which a new version or driver does not have): scenes render with their own kernels")
        elif args.check:
            try:
                b = open_device(d, mode="generic")
                start = time.perf_counter()
                cached = b.built_generic(media=False) is not None and b.opened.cached
                for media in (False, True):
                    b.generic(media)
                line += (f": builds the generic kernels, without media and with ({time.perf_counter() - start + b.opened.seconds:.2f} s"
                         f"{', cached' if cached else ''})")
                seconds, wrong = warm_up(b)
                if wrong and b.refuse_generic():
                    line += (f", and they render wrongly here ({wrong}): scenes render with their own kernels, "
                             "built before their first image")
                elif wrong:
                    line += (f", and they render wrongly here ({wrong}); the kernel cache is not writable, so no "
                             "generic kernels are kept for renders to use")
                else:
                    line += f" and renders with them ({seconds:.2f} s, their first launches' compiling included)"
                builds = True
            except cl.Error as e:
                line += f": cannot build the kernels: {build_error_line(e)}"
        if args.check:
            try:
                line += f"; builds two BVHs ({warm_builder(b or open_device(d, mode='specialised')):.2f} s)"
                builds = True               # its compiler works: scenes' own kernels build too
            except cl.Error as e:
                line += f"; cannot build the BVH builder: {build_error_line(e)}"
        print(line)
        building += builds
    if args.check and not building:
        # install.sh reports a set-up that renders nothing by this status
        raise UserError("no OpenCL device here builds the kernels (the lines above say why)")
    return 0


def cmd_scenes(args):
    from pathtrace.scene.builtin import BUILTIN_SCENES
    for name in BUILTIN_SCENES:
        print(name)
    for name, what in GENERATED_SCENES:
        print(f"{name}: {what}")
    return 0


def warm_up(backend) -> tuple:
    """Renders a few samples of small built-in scenes with `backend`'s generic programs, without
    media and with, with and without next-event estimation, so that a driver that compiles
    kernels at their first launch (PoCL, for each work-group size) has them in its cache before
    a user's first image; the seconds it took, and what was wrong with the renders ("" where
    nothing was): every pixel of these scenes keeps each of its samples, none of which is NaN
    or infinite in a sound program, a count it cannot get wrong (NVIDIA's driver 580 compiled
    the generic program's calls so that pixels counted from a third to three times their
    samples, and their radiance with them: docs/notes/performance-2026-11.md, 2026-11-30)."""
    from pathtrace.rendering.renderer import Renderer
    from pathtrace.scene import load_scene
    generic = backend.with_mode("generic")
    start = time.perf_counter()
    wrong = ""
    for scene in (load_scene("simple"), fog()):
        for nee in (True, False):
            r = Renderer(generic, scene.with_settings(nee=nee), 8, 8)
            r.set_aovs(True)
            r.add_samples(4)
            r.finish()
            kept = r.read_sum()[..., 3]
            if not wrong and (kept != r.samples).any():
                wrong = (f"{scene.name}: pixels kept {kept.min():.0f} to {kept.max():.0f} of "
                         f"{r.samples} samples")
    return time.perf_counter() - start, wrong


def warm_builder(backend) -> float:
    """Builds a BVH over 4,096 boxes and one over 262,144 on `backend`, so that the BVH builder's
    kernels are built and in the drivers' caches before a user's first new scene needs a tree:
    PoCL compiles each kernel at its first launch on a small grid and again on a large one (those
    two sizes launch all twenty), 0.3-0.4 s of the first tree of a large scene after an install
    on two cores (docs/notes/performance-2026-11.md, 2026-11-30, sixteenth session). The seconds
    it took."""
    import numpy as np
    from pathtrace.compiler.bvh import build_bvh
    start = time.perf_counter()
    rng = np.random.default_rng(1)
    for n in (4096, 262144):
        lo = rng.random((n, 3), np.float32)
        build_bvh(lo, lo + np.float32(0.01), num_spheres=0, queue=backend.queue)
    return time.perf_counter() - start


def fog():
    """A sphere of fog (the warm-up's scene with a medium)."""
    from pathtrace.scene.toml_reader import read_scene_dict
    return read_scene_dict({"media": {"fog": {"sigma_a": 0.1, "sigma_s": 0.5}},
                            "spheres": [{"center": [0, 0, 0], "radius": 1, "material": {"type": "null"},
                                         "interior": "fog"}]}, "fog")


def add_parser(sub):
    """The `devices` and `scenes` commands' parsers."""
    p = sub.add_parser("devices", help="list OpenCL platforms and devices")
    p.add_argument("--check", action="store_true", help="also build the generic kernels on each and render with them once, which fills the drivers' caches (pathtrace.device.programs) and checks that each pixel kept its samples: where not, no render uses them; and build two BVHs, for the BVH builder's kernels")
    p.set_defaults(func=cmd_devices)

    p = sub.add_parser("scenes", help="list the built-in scenes")
    p.set_defaults(func=cmd_scenes)
