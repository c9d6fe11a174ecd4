"""Where a render's time goes, tracing against the rest (`pathtrace bench --trace-split`): the
megakernel's depth-2 paths timed against the same kinds of rays traced by a kernel that does
nothing but walk the BVH (kernels/trace_split.cl). Where the walk alone takes nearly the
megakernel's time, the traversal is the cost, and splitting tracing from shading into kernels of
their own (a wavefront path tracer) cannot gain more than the difference; where it takes longer,
the megakernel's coherence wins outright."""

import time
from dataclasses import dataclass, replace

import numpy as np
import pyopencl as cl

from pathtrace.device.opencl import build_program, check_fits
from pathtrace.errors import UserError
from pathtrace.rendering.renderer import Renderer
from pathtrace.resources import resource_dir

RAY_KINDS = ("camera", "bounce", "shadow")      # the rays of kernels/trace_split.cl, in its order


@dataclass
class TraceSplit:
    megakernel_ms: float        # per sample per pixel of the image: the depth-2 paths, whole
    record_ms: float            # writing their rays: the camera ray's walk, then the first vertex's samples
    trace_ms: dict              # per kind of RAY_KINDS: those rays traced alone
    rays_per_pixel: dict        # per kind: the rays recorded per pixel and sample

    @property
    def traced_ms(self) -> float:
        return sum(self.trace_ms.values())

    @property
    def shading_ms(self) -> float:
        """What the recording kernel does beyond its camera rays' walk: the first vertex's
        surface, material, light sample and BSDF sample, the least a wavefront's shading kernel
        would take for these paths."""
        return max(self.record_ms - self.trace_ms["camera"], 0.0)


def split_renderer(backend, scene, width: int, height: int):
    """A renderer of `scene`'s paths of depth 2 with next-event estimation and no roulette, and
    its program with kernels/trace_split.cl's kernels (record_rays, trace_rays), which refuses,
    in one line, scenes whose paths those kernels do not follow."""
    renderer = Renderer(backend, scene.with_settings(max_depth=2, nee=True, russian_roulette="off"), width, height)
    features = renderer.compiled.features(renderer.settings, renderer.camera)
    if renderer.compiled.two_level or features.media:
        what = "a two-level BVH, which its kernels do not walk" if renderer.compiled.two_level \
            else "participating media, whose paths its kernels do not follow"
        raise UserError(f"--trace-split: {scene.name} has {what}")
    program = build_program(backend.context, backend.device.device,
                            (resource_dir("kernels") / "trace_split.cl").read_text(),
                            backend.use_cache, replace(features, traversal_stats=0)).program
    return renderer, program


def trace_split(backend, scene, width: int, height: int, spp: int) -> TraceSplit:
    """The split of `spp` samples per pixel (at least 2: the first launches are not timed) of
    `scene`'s paths of depth 2 with next-event estimation and no roulette, at the scene's seed."""
    renderer, program = split_renderer(backend, scene, width, height)
    queue, local = backend.queue, (8, 8)
    size = tuple(-(-n // l) * l for n, l in zip((width, height), local))
    nbytes = {"rays": width * height * 6 * 16, "hits": width * height * 4}
    check_fits(backend.device.device, nbytes, f"--trace-split at {width}x{height}")
    rays = cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, nbytes["rays"])
    hits = cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, nbytes["hits"])
    record, trace = cl.Kernel(program, "record_rays"), cl.Kernel(program, "trace_rays")

    def seconds(kernel, *args) -> float:
        kernel.set_args(*renderer.scene_args(), *args)
        start = time.perf_counter()
        cl.enqueue_nd_range_kernel(queue, kernel, size, local)
        queue.finish()
        return time.perf_counter() - start

    renderer.add_samples(1)                       # the megakernel's first launch, untimed
    renderer.finish()
    renderer.reset()
    start = time.perf_counter()
    for _ in range(spp - 1):
        renderer.add_samples(1)
    renderer.finish()
    megakernel = time.perf_counter() - start
    recorded, traced, counts = 0.0, np.zeros(3), np.zeros(3)
    for sample in range(spp):                     # the first, untimed: PoCL compiles at first launch
        params = renderer.params(1)
        params["sample_start"], params["row_end"] = sample, height
        took = seconds(record, params, rays)
        recorded += took if sample else 0.0
        for k in range(3):
            took = seconds(trace, params, rays, np.int32(k), hits)
            traced[k] += took if sample else 0.0
            if not sample:
                out = np.empty(width * height, np.int32)
                cl.enqueue_copy(queue, out, hits)
                counts[k] = np.count_nonzero(out != -2)
    per = 1e3 / (spp - 1)
    return TraceSplit(megakernel * per, recorded * per, dict(zip(RAY_KINDS, traced * per)),
                      dict(zip(RAY_KINDS, counts / (width * height))))


def format_split(s: TraceSplit) -> str:
    each = ", ".join(f"{k} {s.trace_ms[k]:.3f}" for k in RAY_KINDS)
    rays = sum(s.rays_per_pixel.values())
    return (f"{'':<20} trace split (depth 2, ms per spp): megakernel {s.megakernel_ms:.3f}; its "
            f"{rays:.2f} rays per pixel traced alone {s.traced_ms:.3f} ({each}), "
            f"{s.traced_ms / s.megakernel_ms:.0%} of it; the first vertex's shading {s.shading_ms:.3f}")
