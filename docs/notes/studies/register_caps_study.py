"""Scenes' programs under forced register caps on NVIDIA's OpenCL, against the cap that
app/device/occupancy.py's tuning chooses (docs/notes/performance-2026-11.md, 2026-11-26 and 2026-11-27):

  python docs/notes/studies/register_caps_study.py SCENE... [--queue 0 1] [--caps 128 96] [--spp 32]
      for each scene and path_queue setting (render setting; 0: off), the program as tuned and
      then built under each cap with -cl-nv-maxrregcount, spills allowed (the tuning and the
      program cache bypassed): milliseconds per sample per pixel of two renders after two
      untimed samples (depth 8, next-event estimation, no roulette), and per render kernel the
      registers and bytes of spill stores from ptxas's report

Prints one JSON line per row."""

import argparse
import json
from contextlib import contextmanager
from dataclasses import replace

import pyopencl as cl

import pathtrace.device.opencl as device
from path_queue_study import settings, timed
from pathtrace.device.occupancy import REPORT, is_nvidia, kernel_registers
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene

RENDER_KERNELS = ("render", "continue_paths")     # with _nee where the scene has it


@contextmanager
def forced_cap(backend, cap: int):
    """A backend of the same device whose programs are built under `cap` (with ptxas's report),
    not tuned, and neither read from nor written to the program cache."""
    tuned = device.build_for_occupancy
    capped = [f"-cl-nv-maxrregcount={cap}", REPORT]
    device.build_for_occupancy = lambda context, dev, source, options: (
        cl.Program(context, source).build(options=options + capped, devices=[dev]), options + capped)
    try:
        yield replace(backend, use_cache=False)     # its own programs (Backend.program_for)
    finally:
        device.build_for_occupancy = tuned


def row(backend, scene, queue: int, spp: int, size, cap: int = None) -> dict:
    r = Renderer(backend, scene.with_settings(**settings(8, queue)), *size)
    times = [round(timed(r, spp)[0], 4) for _ in range(2)]
    dev = backend.device.device
    options = r.program.get_build_info(dev, cl.program_build_info.OPTIONS).split()
    report = kernel_registers(r.program.get_build_info(dev, cl.program_build_info.LOG)) if cap else {}
    return dict(scene=scene.name, path_queue=queue, cap=cap or "as tuned",
                options=[o for o in options if "maxrregcount" in o], ms_per_spp=times,
                registers_spilled={k: list(v) for k, v in report.items() if k.startswith(RENDER_KERNELS)})


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--device", default="gpu")
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--queue", type=int, nargs="+", default=[0])
    ap.add_argument("--caps", type=int, nargs="+", default=[128, 96])
    args = ap.parse_args()
    backend = device.choose_device(args.device)
    if not is_nvidia(backend.device.device):
        raise SystemExit(f"register caps are NVIDIA's: {backend.device.describe()} has none")
    size = tuple(int(v) for v in args.size.split("x"))
    for name in args.scenes:
        scene = load_scene(name)
        for queue in args.queue:
            print(json.dumps(row(backend, scene, queue, args.spp, size)), flush=True)
            for cap in args.caps:
                with forced_cap(backend, cap) as capped:
                    print(json.dumps(row(capped, scene, queue, args.spp, size, cap)), flush=True)


if __name__ == "__main__":
    main()
