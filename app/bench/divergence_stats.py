"""How much of a warp's width the path tracer's shading uses (`pathtrace bench --divergence`):
the megakernel (kernels/integrator.cl: trace_path) loops once per ray of a path, and a GPU runs
32 paths (a warp; AMD's wavefront: 64) in lock step, so that every branch that some lane of a
warp takes, all its lanes wait through: a warp whose lanes hit four BSDF types runs four BSDFs'
code, each with a few lanes. The render kernels, built with DIVERGENCE_STATS
(app/device/features.py; kernels/divergence.cl), record for each work-item and each iteration of
the loop what it shaded: the branch it took after tracing its ray (the BSDF type of the surface
it shaded, or the environment, an emitter at the last vertex, a null surface, a medium), the
material row it shaded, the light type its next-event estimation sampled, and how many image
textures it looked up. The
host groups the work-items into warps of `warp` lanes in the order GPUs form them (consecutive
linear ids of a work-group, x fastest: CUDA C++ Programming Guide, "SIMT Architecture") and
counts, under the model of that guide: a warp runs iteration k of its loop while any of its
lanes does, and runs each branch that any of its active lanes takes, once, with the others
masked off. The counts are the model's, not the hardware's: a compiler may predicate a short
branch, and since Volta a warp may interleave diverged branches; nothing here is timed.

The metrics (each a ratio of sums, hence a mean over warp-executions):

- warp-iteration: a (warp, sample, iteration k) in which at least one lane traces its ray.
- active share: lanes tracing their ray / (warp x warp-iterations): the SIMD efficiency of Aila
  and Laine ("Understanding the Efficiency of Ray Traversal on GPUs", HPG 2009, section 1: the
  share of lanes doing useful work while the warp runs), of the path loop.
- efficiency of a branch b: lanes that take b / (warp x warp-iterations in which some lane takes
  b): the share of the warp enabled while b's code runs, Nsight's "control flow efficiency" (per
  instruction executed, the threads enabled over the warp's width, averaged: Nsight Visual
  Studio Edition, "Instruction Count" experiment) restricted to b. Its complement is the idle
  lanes' share, whether they ended their paths or took another branch.
- shading efficiency: the same pooled over the shading branches (each active lane takes one an
  iteration): the sum of their lanes over warp x the sum of their executions. BSDF efficiency
  pools the BSDF types' branches alone; light efficiency the light types' branches of
  next-event estimation.
- distinct BSDF types: over the warp-iterations in which some lane shades a BSDF, the mean number
  of BSDF types its lanes shade: how many BSDFs' code the warp runs one after another (a blend's
  is the component it chose). Distinct materials: the same of the rows of the material table
  (a blend's own row), whose parameters and textures differ even where their code does not.
- texture lookups per ray: image texture lookups (kernels/textures/bitmap.cl: eval_bitmap and
  grad_bitmap, a bilinear one reading four texels; opacity masks met by the path's rays included)
  over the lanes tracing a ray, i.e. per ray of a path (shadow rays are not counted as rays).

With the continuation queue (path_queue), the render launch records the iterations before a
path waits, and each pass of continue_paths those it traces: its work-items, a queue entry each,
form warps as 1-D work-groups do (consecutive ids), so that the figures show how the queue's
compaction, and with path_sort its sorting by ray (kernels/path_sort.cl), regroup the
paths. A pass's warp-iterations count as the iteration its paths are at, numbered from the
camera ray as the megakernel's. Paths longer than the iterations recorded go on unrecorded (the
kernels record one iteration more, which says how many: DivergenceStats.unrecorded)."""

from dataclasses import dataclass

import numpy as np
import pyopencl as cl

from pathtrace.errors import UserError
from pathtrace.rendering.renderer import MAX_LAUNCH_SAMPLES, PIXEL_GROUP, Renderer

FIELDS = ("shading", "textures", "light", "material low", "material high")   # kernels/divergence.cl: LOG_*
SHADING_NAMES = {1: "traced, ended", 2: "escaped", 3: "last vertex", 4: "null surface", 5: "medium"}
SHADING_BSDF = 6                                # kernels/divergence.cl: SHADING_*, a BSDF's tag added
MAX_ITERATIONS = 64       # iterations recorded where the scene bounds no depth (Russian roulette alone)
RECORD_BYTES = 1 << 28    # the records of one launch at most: a launch renders fewer samples beyond
GROUP = PIXEL_GROUP[0] * PIXEL_GROUP[1]    # work-items per work-group of the render launches


@dataclass
class Branch:
    name: str             # "bsdf diffuse", "light area", "escaped", "image textures", ...
    executions: int       # warp-iterations in which some lane took it
    lanes: int            # lanes that took it
    efficiency: float     # lanes / (warp x executions)


@dataclass
class Iteration:
    iteration: int        # of the loop, from 0 (the camera ray); None: all iterations together
    executions: int       # warp-iterations
    active_share: float
    shading_efficiency: float
    bsdf_efficiency: float          # None where no lane shaded a BSDF
    distinct_bsdfs: float           # None where no lane shaded a BSDF
    distinct_materials: float       # None where no lane shaded a BSDF
    light_efficiency: float         # None where no lane sampled a light
    texture_lookups_per_ray: float


@dataclass
class DivergenceStats:
    warp: int               # lanes per warp
    iterations: int         # iterations recorded per path
    paths: int              # pixels x samples
    unrecorded: float       # the share of paths that went on past the iterations recorded
    overall: Iteration
    per_iteration: list     # of Iteration, those some warp ran
    branches: list          # of Branch, all iterations together, by executions


def shading_name(code: int) -> str:
    from pathtrace.materials.registry import TAGS
    if code >= SHADING_BSDF:
        return "bsdf " + {t: n for n, t in TAGS.items()}[code - SHADING_BSDF]
    return SHADING_NAMES[code]


def light_name(code: int) -> str:
    from pathtrace.lights.registry import LIGHTS
    return "light " + (LIGHTS[code - 1] if code - 1 < len(LIGHTS) else "tree (none chosen)")  # LIGHT_TREE_ROOT


def check_warp(warp: int):
    """A warp of `warp` lanes must be a whole part of a work-group, as GPUs form them."""
    if warp < 1 or GROUP % warp:
        raise UserError(f"a warp of {warp} lanes: its width must divide the {GROUP} work-items of a work-group")


class Tally:
    """The sums of the metrics, per iteration, over the records added."""

    def __init__(self, iterations: int, warp: int):
        check_warp(warp)
        self.warp = warp
        self.executions = np.zeros(iterations, np.int64)   # warp-iterations
        self.active = np.zeros(iterations, np.int64)       # lanes tracing their ray
        self.lookups = np.zeros(iterations, np.int64)      # image texture lookups
        self.distinct = np.zeros(iterations, np.int64)     # BSDF types summed over warp-iterations
        self.materials = np.zeros(iterations, np.int64)    # materials summed over warp-iterations
        self.shading_bsdfs = np.zeros(iterations, np.int64)   # warp-iterations shading a BSDF
        self.branches = {}       # (field, code) -> per-iteration [lanes, executions]
        self.unrecorded = 0      # paths that went on past the iterations

    def add(self, records: np.ndarray):
        """records: uint8 (samples, iterations + 1, FIELDS, lanes), the lanes in warp order, the last
        iteration's only to say which paths went on."""
        self.unrecorded += int(np.count_nonzero(records[:, -1, 0]))
        records = records[:, :-1]
        samples, iterations, _, lanes = records.shape
        warps = records.reshape(samples, iterations, len(FIELDS), lanes // self.warp, self.warp)
        shading, textures, light, low, high = (warps[:, :, f] for f in range(len(FIELDS)))
        # the distinct nonzero material rows of each warp: where the sorted rows change, or begin
        rows = np.sort(low.astype(np.uint16) | (high.astype(np.uint16) << 8), axis=-1)
        distinct = (rows[..., 0] > 0) + ((rows[..., 1:] != rows[..., :-1]) & (rows[..., 1:] > 0)).sum(-1)
        self.materials += distinct.sum((0, 2))
        active = (shading > 0).sum(-1)           # (samples, iterations, warps)
        self.executions += (active > 0).sum((0, 2))
        self.active += active.sum((0, 2))
        self.lookups += textures.sum((0, 2, 3), dtype=np.int64)
        self.shading_bsdfs += (shading >= SHADING_BSDF).any(-1).sum((0, 2))
        for field, values in (("shading", shading), ("light", light)):
            for code in np.flatnonzero(np.bincount(values.ravel(), minlength=256)):
                if code:
                    taking = (values == code).sum(-1)
                    if field == "shading" and code >= SHADING_BSDF:
                        self.distinct += (taking > 0).sum((0, 2))
                    self._count((field, int(code)), taking)
        self._count(("textures", 1), (textures > 0).sum(-1))

    def _count(self, key, taking):
        sums = self.branches.setdefault(key, np.zeros((2, len(self.executions)), np.int64))
        sums[0] += taking.sum((0, 2))
        sums[1] += (taking > 0).sum((0, 2))

    def _pooled(self, keys, k) -> float:
        """The efficiency of the branches `keys` together at iteration slice k (None: never run)."""
        lanes = sum(self.branches[key][0][k].sum() for key in keys)
        executions = sum(self.branches[key][1][k].sum() for key in keys)
        return float(lanes / (self.warp * executions)) if executions else None

    def iteration(self, k, index) -> Iteration:
        """The metrics of iteration slice k (a slice of all of them for the overall row)."""
        shading = [key for key in self.branches if key[0] == "shading"]
        bsdfs = [key for key in shading if key[1] >= SHADING_BSDF]
        lights = [key for key in self.branches if key[0] == "light"]
        shaded = self.shading_bsdfs[k].sum()
        executions, active = int(self.executions[k].sum()), int(self.active[k].sum())
        return Iteration(index, executions, active / (self.warp * executions), self._pooled(shading, k),
                         self._pooled(bsdfs, k), float(self.distinct[k].sum() / shaded) if shaded else None,
                         float(self.materials[k].sum() / shaded) if shaded else None,
                         self._pooled(lights, k), float(self.lookups[k].sum() / active))

    def stats(self, paths: int) -> DivergenceStats:
        names = {"shading": shading_name, "light": light_name, "textures": lambda code: "image textures"}
        branches = [Branch(names[field](code), int(sums[1].sum()), int(sums[0].sum()),
                           float(sums[0].sum() / (self.warp * sums[1].sum())))
                    for (field, code), sums in self.branches.items() if sums[1].sum()]
        ran = [k for k in range(len(self.executions)) if self.executions[k]]
        return DivergenceStats(self.warp, len(self.executions), paths, self.unrecorded / paths,
                               self.iteration(slice(None), None), [self.iteration(k, k) for k in ran],
                               sorted(branches, key=lambda b: -b.executions))


def recorded_iterations(max_depth: int) -> int:
    """The loop's iterations recorded per path: one per vertex up to the scene's max depth."""
    return min(max_depth, MAX_ITERATIONS) if max_depth > 0 else MAX_ITERATIONS


def divergence_stats(backend, scene, width: int, height: int, spp: int, warp: int = 32,
                     iterations: int = None) -> DivergenceStats:
    """The metrics of `spp` samples per pixel of `scene` (a Scene) at its settings, seed 0, with
    `warp` lanes per warp, recording `iterations` iterations per path (default
    recorded_iterations)."""
    if scene.settings.integrator != "path":
        raise UserError(f"{scene.name}: the divergence stats follow the path tracer (integrator 'path'), "
                        f"not '{scene.settings.integrator}'")
    tally = Tally(iterations or recorded_iterations(scene.settings.max_depth), warp)
    renderer = Renderer(backend, scene, width, height)
    (columns, rows), _ = renderer.launch_grid(height)
    recorded = len(tally.executions) + 1                 # one more, to count the paths that go on
    per_sample = recorded * len(FIELDS) * columns * rows
    queued = renderer.queue_plan()[1]
    # with the queue, each pass records a sample's paths as one (at most one queue entry each)
    per_pass_sample = recorded * len(FIELDS) * width * height if queued else 0
    passes = renderer.queue_passes() + 1
    batch = max(1, min(spp, MAX_LAUNCH_SAMPLES, RECORD_BYTES // (per_sample + passes * per_pass_sample)))
    if queued:
        batch = min(batch, renderer.queue_samples(width, height))     # one render launch a batch

    def pass_lanes(count):    # the work-items of each pass after a launch of `count` samples
        launch = {"row_start": 0, "row_end": height, "sample_count": count}
        return renderer.queue_launch_size(launch, renderer.queue_capacity(width, height))

    records = cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, batch * per_sample)
    passes = tuple(cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, recorded * len(FIELDS) * pass_lanes(batch))
                   for _ in range(passes)) if queued else ()
    renderer.record_shading(records, recorded, passes)
    host = np.empty((batch, recorded, len(FIELDS), columns * rows), np.uint8)
    for start in range(0, spp, batch):
        count = min(batch, spp - start)
        for buffer in (records, *passes):
            cl.enqueue_fill_buffer(backend.queue, buffer, np.uint8(0), 0, buffer.size)
        renderer.add_samples(count)
        cl.enqueue_copy(backend.queue, host, records)
        tally.add(host[:count])
        for buffer in passes:
            taken = np.empty((1, recorded, len(FIELDS), pass_lanes(count)), np.uint8)
            cl.enqueue_copy(backend.queue, taken, buffer)
            tally.add(taken)
    renderer.finish()
    return tally.stats(width * height * spp)


HEADER = (f"{'iteration':>9} {'warp-its':>9} {'active':>7} {'shading':>8} {'bsdf':>6} {'types':>6} "
          f"{'mats':>6} {'light':>6} {'tex/ray':>7}")


def format_stats(s: DivergenceStats) -> str:
    """The table of the metrics: a row per iteration and one for all, then each branch's."""
    def share(x):
        return "-" if x is None else f"{x:.3f}"

    def mean(x):
        return "-" if x is None else f"{x:.2f}"

    def row(it: Iteration, label):
        return (f"{label:>9} {it.executions:>9} {share(it.active_share):>7} {share(it.shading_efficiency):>8} "
                f"{share(it.bsdf_efficiency):>6} {mean(it.distinct_bsdfs):>6} {mean(it.distinct_materials):>6} "
                f"{share(it.light_efficiency):>6} {it.texture_lookups_per_ray:>7.2f}")
    lines = [f"divergence in warps of {s.warp} ({s.paths} paths, {s.iterations} iterations recorded; "
             f"{s.unrecorded:.4f} of the paths went on past them)", HEADER]
    lines += [row(it, it.iteration) for it in s.per_iteration] + [row(s.overall, "all")]
    lines.append(f"{'branch':<28} {'warp-its':>9} {'lanes':>11} {'efficiency':>10}")
    lines += [f"{b.name:<28} {b.executions:>9} {b.lanes:>11} {b.efficiency:>10.3f}" for b in s.branches]
    return "\n".join(lines)
