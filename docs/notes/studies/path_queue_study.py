"""Where a render's time goes along its paths (docs/notes/performance-2026-11.md, 2026-11-26):

  python docs/notes/studies/path_queue_study.py depths SCENE... [--device gpu] [--size WxH] [--spp N]
      the megakernel's milliseconds per sample per pixel at max depth 1, 2, 3, 4, 6 and 8 (next-event
      estimation, no roulette): what each further vertex costs, however few paths reach it
  python docs/notes/studies/path_queue_study.py passes SCENE... [--queue 1 2] [...]
      with the continuation queue (render setting path_queue): each kernel's time per sample (the
      render launch, each pass of continue_paths, add_queued_paths, from the queue's profiling
      events) and the paths each pass took in the last launch

Prints one JSON line per row."""

import argparse
import json
import time

import numpy as np
import pyopencl as cl

from pathtrace.device.opencl import choose_device
from pathtrace.rendering.renderer import QUEUE_PASSES, Renderer
from pathtrace.scene import load_scene

DEPTHS = (1, 2, 3, 4, 6, 8)


def settings(depth: int, queue: int = 0) -> dict:
    return dict(max_depth=depth, russian_roulette="off", nee=True, path_queue=queue)


def timed(r: Renderer, spp: int) -> tuple:
    r.add_samples(2)                         # builds and warms the kernels
    r.finish()
    start = time.perf_counter()
    events = r.add_samples(spp)
    r.finish()
    return (time.perf_counter() - start) * 1000 / spp, events


def depths(backend, scene, size, spp):
    for depth in DEPTHS:
        ms, _ = timed(Renderer(backend, scene.with_settings(**settings(depth)), *size), spp)
        print(json.dumps(dict(scene=scene.name, max_depth=depth, ms_per_spp=round(ms, 4))), flush=True)


def passes(backend, scene, size, spp, queues):
    for queue in queues:
        r = Renderer(backend, scene.with_settings(**settings(8, queue)), *size)
        ms, events = timed(r, spp)
        per_launch = QUEUE_PASSES + 4          # fill, render, the passes, add_queued_paths
        kernel_ms = [(e.profile.end - e.profile.start) * 1e-6 for e in events]
        column = lambda k: round(sum(kernel_ms[k::per_launch]) / spp, 4)
        counters = np.zeros(QUEUE_PASSES + 2, np.int32)
        cl.enqueue_copy(backend.queue, counters, r.buffer("counters"))
        print(json.dumps(dict(scene=scene.name, path_queue=queue, ms_per_spp=round(ms, 4), render=column(1),
                              passes=[column(2 + k) for k in range(QUEUE_PASSES + 1)],
                              add_queued_paths=column(per_launch - 1),
                              paths_per_pass_last_launch=counters[:-1].tolist())), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=("depths", "passes"))
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--device", default="gpu")
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--queue", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    backend = choose_device(args.device)
    size = tuple(int(v) for v in args.size.split("x"))
    for name in args.scenes:
        scene = load_scene(name)
        if args.what == "depths":
            depths(backend, scene, size, args.spp)
        else:
            passes(backend, scene, size, args.spp, args.queue)


if __name__ == "__main__":
    main()
