"""Which shapes of kernel PoCL runs in SIMD lanes, an experiment for #31's CPU goal
(docs/notes/performance-2026-11.md, 2026-11-27): a diffuse bounce among five spheres (docs/notes/studies/simd_study.cl)
written one path per work-item in scalar floats, or LANES paths per work-item in OpenCL
vectors, and the whole path in one kernel with and without a barrier at each bounce. Not part
of the renderer.

    python docs/notes/studies/simd_study.py [--device cpu] [--paths 262144] [--depth 8] [--lanes 4 8 16]

Prints, per shape, the best of three runs of DEPTH bounces of every path (in millions of
bounces per second) and the mean radiance, which is the same for every shape: they draw the same
random numbers. `POCL_VECTORIZER_REMARKS=1` (with `POCL_KERNEL_CACHE=0`) makes PoCL say which of
its work-item loops LLVM vectorised."""

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pyopencl as cl

from pathtrace.cli.options import _int_range
from pathtrace.device.opencl import choose_device
from pathtrace.errors import UserError

HERE = Path(__file__).resolve().parent


def lanes_header(lanes: int) -> str:
    """The OpenCL names of kernels written for LANES paths per work-item: floatN, intN and uintN
    (the vector types), their conversions, loads and stores, and LANE_INDEX (0, 1, ... as intN)."""
    indices = ", ".join(str(k) for k in range(lanes))
    return "\n".join([f"#define LANES {lanes}", f"typedef float{lanes} floatN;", f"typedef int{lanes} intN;",
                      f"typedef uint{lanes} uintN;", f"#define convert_floatN convert_float{lanes}",
                      f"#define convert_intN convert_int{lanes}", f"#define as_uintN as_uint{lanes}",
                      f"#define VLOAD vload{lanes}", f"#define VSTORE vstore{lanes}",
                      f"#define LANE_INDEX ((intN)({indices}))", ""])


def build(backend, options: list[str], lanes: int = 0):
    source = (HERE / "simd_study.cl").read_text()
    return cl.Program(backend.context, (lanes_header(lanes) if lanes else "") + source).build(options=options)


def starting_paths(n: int):
    """Camera-like rays from (0, 1, 8) into the spheres, as (3, n) origins and directions."""
    rng = np.random.default_rng(1)
    o = np.zeros((3, n), np.float32)
    o[1], o[2] = 1.0, 8.0
    d = rng.normal(size=(3, n)).astype(np.float32)
    d[2] = -np.abs(d[2]) - 2.0
    return o, d / np.linalg.norm(d, axis=0)


def best_of_three(queue, prepare, n: int) -> tuple:
    """Best of three runs and the mean radiance: prepare() sets a run up (fresh buffers) and
    returns the function that enqueues it and the radiance buffer it writes."""
    best = np.inf
    for _ in range(3):
        run, radiance = prepare()
        queue.finish()
        start = time.perf_counter()
        run()
        queue.finish()
        best = min(best, time.perf_counter() - start)
    out = np.empty(n, np.float32)
    cl.enqueue_copy(queue, out, radiance)
    return best, float(out.mean())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--paths", type=_int_range(16, 1 << 24), default=1 << 18, help="a multiple of 16")
    ap.add_argument("--depth", type=_int_range(1, 64), default=8)
    ap.add_argument("--lanes", type=int, nargs="+", choices=(2, 4, 8, 16), default=[4, 8, 16])
    args = ap.parse_args()
    if args.paths % 16:
        ap.error(f"--paths: {args.paths} is not a multiple of 16")
    try:
        backend = choose_device(args.device)
    except UserError as e:
        sys.exit(f"simd_study: {e}")
    ctx, queue, n = backend.context, backend.queue, args.paths
    o, d = starting_paths(n)
    mf = cl.mem_flags
    print(f"{backend.device.describe()}: {n} paths, {args.depth} bounces each")

    def buffer(host):
        return cl.Buffer(ctx, mf.READ_WRITE | mf.COPY_HOST_PTR, hostbuf=host)

    def bounces(kernel, items: int):
        """A launch of `kernel` over `items` work-items per bounce."""
        def prepare():
            state = [buffer(o), buffer(d), buffer(np.ones(n, np.float32)), buffer(np.zeros(n, np.float32))]

            def run():
                for depth in range(args.depth):
                    kernel(queue, (items,), None, *state, np.int32(n), np.int32(depth))
            return run, state[3]
        return best_of_three(queue, prepare, n)

    def whole_paths(kernel):
        """One launch of `kernel` for the whole paths, in work-groups of 64."""
        def prepare():
            state = [buffer(o), buffer(d), cl.Buffer(ctx, mf.READ_WRITE, 4 * n)]
            return (lambda: kernel(queue, (n,), (64,), *state, np.int32(n))), state[2]
        return best_of_three(queue, prepare, n)

    def report(name, seconds, mean):
        print(f"{name:38s} {seconds * 1e3:8.1f} ms {n * args.depth / seconds / 1e6:8.1f} M bounces/s"
              f"  mean radiance {mean:.6f}", flush=True)

    report("bounce, a path per work-item", *bounces(cl.Kernel(build(backend, []), "bounce"), n))
    for lanes in args.lanes:
        kernel = cl.Kernel(build(backend, [], lanes), "bounce_lanes")
        report(f"bounce_lanes, {lanes} paths per work-item", *bounces(kernel, n // lanes))
    for barrier in (False, True):
        options = [f"-DDEPTH={args.depth}"] + (["-DBOUNCE_BARRIER"] if barrier else [])
        report(f"render{', a barrier per bounce' if barrier else ''}",
               *whole_paths(cl.Kernel(build(backend, options), "render")))


if __name__ == "__main__":
    main()
