"""Embree's walk against pathtrace's on CPUs, an experiment for #31's CPU goal
(docs/notes/performance-2026-11.md, 2026-11-27): the same rays, recorded as the megakernel traces them (the
trace split's record_rays, kernels/trace_split.cl: per pixel a camera ray, and at its hit one
light sample's shadow ray and one BSDF sample's bounce), traced by pathtrace's trace_rays on
the OpenCL device and by Embree 4 (Intel's CPU ray tracing kernels, through the `embreex`
binding: `pip install embreex`) over the same triangles. Not part of the renderer, and embreex
is not one of its dependencies.

    python docs/notes/studies/embree_walk_study.py [SCENE ...] [--size 480x272] [--spp 4] [--threads N]

--threads sets PoCL's threads (POCL_MAX_PTHREAD_COUNT) before the device opens: embreex traces
a batch of rays on one thread, so `--threads 1` compares one core with one core. Prints, per
scene and kind of ray, ms per sample per pixel for each, their ratio, and the share of rays on
whose hit or miss (for shadow rays: occlusion) the two agree. Spheres are not Embree triangles:
a scene's spheres stay in pathtrace's walk (a few outside the tree cost a test each) and are
left out of Embree's, so scenes with more than a few are refused. Embree cannot skip the triangle
a ray leaves, as pathtrace does, so rays leaving a surface start 1e-5 of the scene's radius along
themselves for it."""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path


def main():
    from pathtrace.cli.options import _int_range, _size
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", default=["teapot-sky", "heightfield1M", "tori400-textured"])
    ap.add_argument("--size", type=_size, default=(480, 272), metavar="WxH")
    ap.add_argument("--spp", type=_int_range(1, 1024), default=4)
    ap.add_argument("--threads", type=_int_range(1, 1024))
    args = ap.parse_args()
    if args.threads:
        os.environ["POCL_MAX_PTHREAD_COUNT"] = str(args.threads)

    import numpy as np
    import pyopencl as cl
    try:
        from embreex.mesh_construction import TriangleMesh
        from embreex.rtcore_scene import EmbreeScene
    except ImportError:
        sys.exit("embree_walk_study: Embree's binding is missing: pip install embreex")

    from pathtrace.bench.report import scene_file
    from pathtrace.device.opencl import choose_device
    from pathtrace.errors import UserError
    from pathtrace.device.features import LONE_MAX
    from pathtrace.scene import load_scene
    from pathtrace.bench.trace_split import split_renderer

    width, height = args.size
    backend = choose_device("cpu")
    q = backend.queue
    print(f"{backend.device.describe()}, {args.threads or 'all'} PoCL threads; {width}x{height}, "
          f"depth-2 rays of {args.spp} samples per pixel")
    for name in args.scenes:
        try:
            scene = load_scene(scene_file(name, Path(tempfile.mkdtemp(prefix="pathtrace-embree-"))))
            if len(scene.spheres) > LONE_MAX:
                raise UserError(f"{name}: {len(scene.spheres)} spheres, which Embree's triangles cannot stand for")
            r, program = split_renderer(backend, scene, width, height)
            if r.compiled.num_triangles == 0:
                raise UserError(f"{name}: no triangles for Embree to walk")
        except UserError as e:
            sys.exit(f"embree_walk_study: {e}")
        record, trace = cl.Kernel(program, "record_rays"), cl.Kernel(program, "trace_rays")
        pixels = width * height
        rays = cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, pixels * 96)
        hits = cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, pixels * 4)
        triangles = r.compiled.triangles
        epsilon = 1e-5 * r.compiled.radius
        embree = EmbreeScene()
        TriangleMesh(embree, np.stack([triangles[v][:, :3] for v in ("v0", "v1", "v2")], axis=1).astype(np.float32))
        size = tuple(-(-n // 8) * 8 for n in (width, height))
        ours, theirs, agree, counts = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
        for sample in range(args.spp + 1):          # the first, untimed: PoCL compiles at first launch
            params = r.params(1)
            params["sample_start"], params["row_end"] = sample, height
            record(q, size, (8, 8), *r.scene_args(), params, rays)
            host = np.empty((pixels, 3, 2, 4), np.float32)
            cl.enqueue_copy(q, host, rays)
            for kind in range(3):
                start = time.perf_counter()
                trace(q, size, (8, 8), *r.scene_args(), params, rays, np.int32(kind), hits)
                q.finish()
                mine = time.perf_counter() - start
                found = np.empty(pixels, np.int32)
                cl.enqueue_copy(q, found, hits)
                o, d = host[:, kind, 0], host[:, kind, 1]
                real = np.any(d[:, :3] != 0, axis=1)
                # embreex takes no t_min, and Embree cannot skip the triangle a ray leaves, as
                # pathtrace does (`self`): rays leaving a surface start a little along themselves
                step = np.where(d[real, 3].view(np.int32) >= 0, epsilon, 0.0).astype(np.float32)[:, None]
                directions = np.ascontiguousarray(d[real, :3])
                origins = np.ascontiguousarray(o[real, :3] + step * directions)
                t_max = np.ascontiguousarray(o[real, 3] - step[:, 0])
                start = time.perf_counter()
                embree_hits = embree.run(origins, directions, dists=t_max,
                                         query="OCCLUDED" if kind == 2 else "INTERSECT")
                other = time.perf_counter() - start
                if sample:
                    ours[kind] += mine
                    theirs[kind] += other
                    hit_ours = found[real] != (0 if kind == 2 else -1)
                    agree[kind] += np.count_nonzero(hit_ours == (embree_hits >= 0))
                    counts[kind] += real.sum()
        ms_ours, ms_theirs = ours * 1e3 / args.spp, theirs * 1e3 / args.spp
        for k, kind in enumerate(("camera", "bounce", "shadow")):
            print(f"{name:18s} {kind:6s}  pathtrace {ms_ours[k]:7.2f} ms  Embree {ms_theirs[k]:7.2f} ms  "
                  f"({ms_ours[k] / ms_theirs[k]:.2f}x)  {counts[k] / args.spp:8.0f} rays, "
                  f"agree {agree[k] / counts[k]:.4f}", flush=True)


if __name__ == "__main__":
    main()
