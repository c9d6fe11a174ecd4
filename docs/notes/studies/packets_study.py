"""Rays traced in packets on CPUs, an experiment for #31's CPU goal (docs/notes/performance-2026-11.md,
2026-11-26): how much faster the BVH walk gets when each work-item walks the rays of a tile of
pixels together in SIMD lanes, and a whole render with each tile's paths kept in step
(docs/notes/studies/packets_study.cl). Neither is part of the renderer.

    python docs/notes/studies/packets_study.py walk [--size WxH] [--spp N] [--lanes 4 8 16] [SCENE ...]
    python docs/notes/studies/packets_study.py render [--size WxH] [--spp N] [SCENE ...]

`walk` records the depth-2 rays of the trace split (kernels/trace_split.cl) and traces each kind
by trace_rays (one ray per work-item) and by packets, in turn in one run: ms per sample per
pixel, their ratio, the share of rays whose result the two agree on (primitive for primitive),
and the nodes a packet visits. `render` times depth 8 with next-event estimation by the
megakernel and by the paths in step, best of two rounds each, and compares their images."""

import argparse
import time
from dataclasses import replace
from pathlib import Path
import tempfile

import numpy as np
import pyopencl as cl

from pathtrace.bench.report import estimator_settings, scene_file
from pathtrace.device.opencl import build_program, choose_device
from pathtrace.rendering.renderer import Renderer
from pathtrace.resources import resource_dir
from pathtrace.scene import load_scene

TILES = {4: (2, 2), 8: (4, 2), 16: (4, 4)}      # lanes: the tile of pixels whose rays they hold
HERE = Path(__file__).resolve().parent


def packets_program(backend, renderer, lanes: int):
    """The scene's program with the trace split's kernels and the packets' (LANES wide)."""
    tile_w, tile_h = TILES[lanes]
    header = (f"#define LANES {lanes}\n#define TILE_W {tile_w}\n#define TILE_H {tile_h}\n"
              f"typedef float{lanes} floatN;\ntypedef int{lanes} intN;\n")
    source = "\n".join([(resource_dir("kernels") / "trace_split.cl").read_text(), header,
                        (HERE / "packets_study.cl").read_text()])
    features = renderer.compiled.features(renderer.settings, renderer.camera)
    return build_program(backend.context, backend.device.device, source, backend.use_cache,
                         replace(features, traversal_stats=0)).program


def timed(queue, kernel, size, local, *args) -> float:
    kernel.set_args(*args)
    start = time.perf_counter()
    cl.enqueue_nd_range_kernel(queue, kernel, size, local)
    queue.finish()
    return time.perf_counter() - start


def study_walk(backend, scene, width, height, spp, lanes_list):
    r = Renderer(backend, scene.with_settings(max_depth=2, nee=True, russian_roulette="off"), width, height)
    q = backend.queue
    rays = cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, width * height * 96)
    hits = [cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, width * height * 4) for _ in range(2)]
    size = tuple(-(-n // 8) * 8 for n in (width, height))
    for lanes in lanes_list:
        program = packets_program(backend, r, lanes)
        record, single, packets = (cl.Kernel(program, n) for n in ("record_rays", "trace_rays", "trace_packets"))
        tile_w, tile_h = TILES[lanes]
        whole = (height // tile_h * tile_h, width // tile_w * tile_w)
        count = (width // tile_w) * (height // tile_h)
        visits = cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, count * 4)
        seconds, agree, nodes = np.zeros((2, 3)), np.zeros(3), np.zeros(3)
        for sample in range(spp + 1):           # the first, untimed: PoCL compiles at first launch
            params = r.params(1)
            params["sample_start"], params["row_end"] = sample, height
            timed(q, record, size, (8, 8), *r.scene_args(), params, rays)
            for kind in range(3):
                a = timed(q, single, size, (8, 8), *r.scene_args(), params, rays, np.int32(kind), hits[0])
                b = timed(q, packets, (-(-count // 64) * 64,), (64,), *r.scene_args(), params, rays,
                          np.int32(kind), hits[1], visits)
                if sample:
                    seconds[:, kind] += a, b
                    out = [np.empty(width * height, np.int32) for _ in range(2)]
                    for o, h in zip(out, hits):
                        cl.enqueue_copy(q, o, h)
                    one, two = (o.reshape(height, width)[:whole[0], :whole[1]] for o in out)
                    agree[kind] += np.mean(one == two) / spp
                    v = np.empty(count, np.int32)
                    cl.enqueue_copy(q, v, visits)
                    nodes[kind] += v.mean() / spp
        ms = seconds * 1e3 / spp
        rows = ", ".join(f"{kind} {ms[1, k]:.2f} / {ms[0, k]:.2f} ({ms[1, k] / ms[0, k]:.2f})"
                         for k, kind in enumerate(("camera", "bounce", "shadow")))
        print(f"{scene.name} {width}x{height}, {lanes} lanes, ms per spp, packets / single rays: {rows}; "
              f"results agree {', '.join(f'{a:.4f}' for a in agree)}; nodes per packet "
              f"{', '.join(f'{n:.1f}' for n in nodes)}", flush=True)


def study_render(backend, scene, width, height, spp):
    r = Renderer(backend, scene.with_settings(**estimator_settings("depth8+nee")), width, height)
    q = backend.queue
    render = cl.Kernel(packets_program(backend, r, 8), "render_packets")
    count = (width // 4) * (height // 2)
    sums = cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, width * height * 16)

    def packets(n):
        params = r.params(n)
        params["sample_start"], params["row_end"] = 0, height
        cl.enqueue_fill_buffer(q, sums, np.float32(0), 0, width * height * 16)
        return timed(q, render, (-(-count // 64) * 64,), (64,), *r.scene_args(), params, sums)

    def megakernel(n):
        r.reset()
        r.finish()
        start = time.perf_counter()
        r.add_samples(n)
        r.finish()
        return time.perf_counter() - start

    packets(1), megakernel(1)                      # the first launches, untimed
    mine, theirs = [], []
    for _ in range(2):
        theirs.append(megakernel(spp))
        mine.append(packets(spp))
    image = np.empty((height, width, 4), np.float32)
    cl.enqueue_copy(q, image, sums)
    a, b = r.mean()[: height // 2 * 2, : width // 4 * 4], image[: height // 2 * 2, : width // 4 * 4, :3] / spp
    close = np.mean(np.abs(a - b) <= 1e-4 * np.maximum(a, 1.0))
    print(f"{scene.name} {width}x{height} {spp} spp: megakernel {', '.join(f'{t:.3f}' for t in theirs)} s, "
          f"paths in step {', '.join(f'{t:.3f}' for t in mine)} s: {min(mine) / min(theirs):.2f} of its time; "
          f"image means {a.mean():.5f} and {b.mean():.5f}, {close:.4f} of pixels within 1e-4", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("study", choices=("walk", "render"))
    parser.add_argument("scenes", nargs="*", default=["teapot-sky", "tori400-textured", "heightfield1M",
                                                      "spheres8k-diffuse"])
    parser.add_argument("--size", default="480x272")
    parser.add_argument("--spp", type=int, default=4)
    parser.add_argument("--lanes", type=int, nargs="+", choices=sorted(TILES), default=[8])
    parser.add_argument("--device", default="cpu")
    args = parser.parse_intermixed_args()
    width, height = map(int, args.size.split("x"))
    backend = choose_device(args.device)
    print(backend.device.describe())
    with tempfile.TemporaryDirectory() as folder:
        for name in args.scenes:
            scene = load_scene(scene_file(name, Path(folder)))
            if args.study == "walk":
                study_walk(backend, scene, width, height, args.spp, args.lanes)
            else:
                study_render(backend, scene, width, height, args.spp)


if __name__ == "__main__":
    main()
