"""What differs between a scene's program built without the continuation queue and with it, on
NVIDIA's OpenCL (docs/notes/performance-2026-11.md, 2026-11-27: the queue chosen by trial renders):

  python docs/notes/studies/queue_program_study.py SCENE...

For each scene and path_queue 0 and 1 (render setting), the render kernels' registers and bytes
of spill stores from ptxas's report, untuned and as app/device/occupancy.py tunes them (with the cap it
chose and the warps resident per SM), and the PTX instructions of render_nee. Prints one JSON
line per program."""

import argparse
import json
import re
from dataclasses import replace

import pyopencl as cl

from pathtrace.compiler.compiled import compile_scene
from pathtrace.device.opencl import BUILD_OPTIONS, choose_device, kernel_source
from pathtrace.device.occupancy import REPORT, build_for_occupancy, is_nvidia, kernel_registers, resident_warps
from pathtrace.scene import load_scene

KERNELS = ("render_nee", "continue_paths_nee")


def ptx_instructions(ptx: str, entry: str) -> int:
    """Instructions (not directives, labels or braces) of one entry function of a PTX listing."""
    start = ptx.index(f".entry {entry}")
    end = ptx.find(".entry", start + 1)
    body = ptx[start:end if end >= 0 else len(ptx)]
    return sum(1 for line in body.splitlines()
               if line.strip() and not line.strip().startswith(("//", ".", "$", "{", "}", ")", "(")))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scenes", nargs="+")
    args = p.parse_args()
    backend = choose_device("gpu")
    dev = backend.device.device
    if not is_nvidia(dev):
        raise SystemExit("this study reads ptxas's report: it needs NVIDIA's OpenCL")
    for name in args.scenes:
        scene = load_scene(name).with_settings(max_depth=8, russian_roulette="off", nee=True)
        compiled = compile_scene(scene, backend.queue)
        for queue in (0, 1):
            features = replace(compiled.features(scene.settings, scene.camera), path_queue=queue)
            source = kernel_source("", features)
            options = list(BUILD_OPTIONS) + [f"-D{d}" for d in features.defines()]
            untuned = cl.Program(backend.context, source).build(options=options + [REPORT], devices=[dev])
            tuned, chosen = build_for_occupancy(backend.context, dev, source, options)
            report = kernel_registers(tuned.get_build_info(dev, cl.program_build_info.LOG))
            untuned_report = kernel_registers(untuned.get_build_info(dev, cl.program_build_info.LOG))
            ptx = untuned.binaries[0].decode(errors="replace")
            print(json.dumps(dict(
                scene=scene.name, path_queue=queue,
                untuned={k: v for k, v in untuned_report.items() if k in KERNELS},
                cap=[o for o in chosen if "maxrregcount" in o],
                tuned={k: v for k, v in report.items() if k in KERNELS},
                warps={k: resident_warps(v[0], dev.registers_per_block_nv, dev.warp_size_nv)
                       for k, v in report.items() if k in KERNELS},
                render_nee_ptx_instructions=ptx_instructions(ptx, "render_nee"),
                ptx_calls=len(re.findall(r"\bcall(\.uni)?\b", ptx)))), flush=True)


if __name__ == "__main__":
    main()
