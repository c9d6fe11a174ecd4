"""A scene's own program built by NVIDIA's OpenCL compiler under each `-cl-nv-opt-level`, with its
build time and the time of 32 samples at 640x360 (docs/notes/performance-2026-12.md, twenty-fifth
session: whether a first start could render from a program built faster at a lower level, while
the optimised one builds). Run on a machine with an NVIDIA GPU, the driver's cache off:

    CUDA_CACHE_DISABLE=1 python docs/notes/studies/nv_opt_level.py teapot-sky
"""

import sys
import time

import pyopencl as cl

from pathtrace.device.opencl import choose_device, kernel_source, program_options
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene


def main(scene: str):
    backend = choose_device("gpu")
    device = backend.device.device
    renderer = Renderer(backend, load_scene(scene), 640, 360)
    features = renderer._features("path")
    source, options = kernel_source("", features), program_options(device, features)
    for extra in ([], ["-cl-nv-opt-level=0"], ["-cl-nv-opt-level=1"], ["-cl-nv-opt-level=2"]):
        start = time.perf_counter()
        program = cl.Program(backend.context, source).build(options=options + extra, devices=[device])
        built = time.perf_counter() - start
        renderer._use_program(program, generic=False)
        renderer.reset()
        renderer.add_samples(4)
        renderer.finish()
        start = time.perf_counter()
        for _ in range(8):
            renderer.add_samples(4)
        renderer.finish()
        print(f"{' '.join(extra) or 'default'}: build {built:.2f} s, 32 spp {time.perf_counter() - start:.3f} s", flush=True)


if __name__ == "__main__":
    main(sys.argv[1])
