"""The progressive renderer: device buffers for a scene and an accumulation buffer, to which
each add_samples() call adds samples per pixel. The command line, the benchmarks and the viewer
all drive this API; it imports nothing from the window or the GUI."""

import threading
from dataclasses import replace

import numpy as np
import pyopencl as cl

from pathtrace.rendering.path_sort import SORT_BUFFERS, PathSort
from pathtrace.rendering.photons import PHOTON_BUFFERS, PhotonPasses
from pathtrace.rendering.program_choice import ProgramChoice
from pathtrace.rendering.queue_plans import QueuePlans
from pathtrace.cameras import KERNELS as CAMERA_KERNELS, Camera
from pathtrace.compiler.compiled import SCENE_BUFFERS, CompiledScene, compile_scene
from pathtrace.device.opencl import Backend, check_fits
from pathtrace.errors import UserError, format_bytes
from pathtrace.scene.environment import Environment
from pathtrace.compiler.memory import available_host_memory
from pathtrace.scene import Scene
from pathtrace.filters import FILTERS
from pathtrace.rendering.choices import RUSSIAN_ROULETTE
from pathtrace.device.types import PATH_RECORD, RENDER_PARAMS

RR_DEPTH = 5           # where Russian roulette on throughput starts (Mitsuba 3's default)
READ_BACK_BYTES = 64   # host memory per pixel to read an image back and write it: the float4
                       # sums, the float32 mean and the encoded copies
AOV_PASSES = 16        # the denoiser's albedo and normal are accumulated over the first passes
                       # only: by then they hardly change (kernels/aovs.cl takes 4 BSDF samples
                       # a pass), and the path tracer runs at full speed after
AOV_BUFFERS = ("albedo_sum", "normal_sum")   # kernels/aovs.cl: albedo rgb and the samples
                                             # kept in w; normal xyz and the depth in w


SUM_BUFFERS = ("sum", "sum_sq", "sum_c", "sum_sq_c")   # kernels/integrator.cl: the sums and
                                                       # what their rounding lost (Kahan)
PIXEL_GROUP = (8, 8)      # the work-group of the render launches: 8x8 pixels (launch_grid)
MAX_LAUNCH_SAMPLES = 64   # samples a launch adds to a pixel, summed plainly in float32 before the
                          # compensated running sum takes them: within 64 ulps of their sum
QUEUE_PASSES = 4          # passes of continue_paths that trace one vertex each, queueing the paths
                          # that go on again; a last pass traces them to their ends
QUEUE_POOL = 1 << 23      # pixel samples a launch with the queue renders (a few per pixel): enough
                          # paths going on to fill a GPU when continue_paths traces them, and the
                          # passes' cost per launch spread (docs/notes/performance-2026-11.md, 2026-11-26)
QUEUE_GROUP = 64          # work-items per group of continue_paths (32 and 128 were no faster:
                          # docs/notes/performance-2026-11.md, 2026-11-26)
MAX_QUEUED = 1 << 23      # entries of each of the two queues (PATH_RECORD, 128 bytes; at most a
                          # sixteenth of the device's memory); paths that find one full go on
                          # where they are
SORT_PASSES = 16          # with path_sort, the most passes of one vertex (queue_passes)


def image_buffers(aovs: bool) -> tuple:
    """The per-pixel float4 buffers: the sums, and with `aovs` the denoiser's albedo and normal."""
    return SUM_BUFFERS + (AOV_BUFFERS if aovs else ())


def per_pixel_mean(sums: np.ndarray) -> np.ndarray:
    """rgb / w of float4 sums whose w counts each pixel's samples (0 where there are none):
    the mean of a pass under way, whose rows differ by a sample."""
    w = sums[..., 3:4]
    return np.divide(sums[..., :3], w, out=np.zeros(sums.shape[:-1] + (3,), np.float32), where=w > 0)


def aov_means(albedo_sum: np.ndarray, normal_sum: np.ndarray) -> dict:
    """The auxiliary images from their sums (kernels/aovs.cl), each (H, W, 3) float32 but the
    depth (H, W): "albedo" (clamped to [0, 1], the denoiser's range), "normal" and "depth"."""
    w = albedo_sum[..., 3:4]
    sums = np.concatenate([albedo_sum[..., :3], normal_sum], axis=-1)
    means = np.divide(sums, w, out=np.zeros(sums.shape, np.float32), where=w > 0)
    return {"albedo": np.clip(means[..., :3], 0.0, 1.0), "normal": means[..., 3:6], "depth": means[..., 6]}


def variance_of(sum: np.ndarray, sum_sq: np.ndarray, samples: int) -> np.ndarray:
    """The per-sample variance of each pixel and channel from the running sums of `samples`
    samples (of one sample, not of the mean)."""
    n = max(samples, 1)
    m = sum[..., :3].astype(np.float64) / n
    return np.maximum(sum_sq[..., :3] / n - m * m, 0.0).astype(np.float32)


# held while a renderer sets its compiled scene's light sampler (Renderer.set_scene)
_LIGHT_SAMPLER_LOCK = threading.Lock()


class Renderer(ProgramChoice, QueuePlans, PathSort, PhotonPasses):
    def __init__(self, backend: Backend, scene, width: int = None, height: int = None, progress=None,
                 all_kernels: bool = False, settings=None, aovs: bool = False):
        """scene: a CompiledScene, or a Scene to compile (on this device, calling progress(fraction)
        as its BVH build goes). all_kernels: its programs hold every kernel, both estimators', the
        AOVs' and picking's, as the viewer's do (app/device/features.py: KERNEL_SETS); else they
        hold what its passes launch, and the AOVs and picking come from a program of their own.
        settings (default: the scene's) and aovs (set_aovs) are the first render's, for which its
        programs start building beside the tree (set_scene)."""
        self.backend = backend
        self.all_kernels = all_kernels
        self.program = None       # the kernels launches run (_select_program)
        self._kernel_names = set()  # the names of its kernels
        self.uses_generic_program = False
        self._awaited = None      # the features of the scene's own program while it builds
        self._build_due = False   # whether a pass is drawn, after which that build may start
        self._buffers = {}
        self.width = self.height = 0
        self._queued_for = None   # whether the queue's buffers are sized for launches that use it
        self.auto_plan = None     # with path_queue "auto": the plan its trials chose (choose_queue_plan)
        self.plan_seconds = {}    # and the seconds of each plan's fastest trial
        self.plan_cached = False  # whether it is the verdict of earlier trials (_plan_verdict_path)
        self.samples = 0          # samples per pixel accumulated so far (whole passes)
        self.generic_samples = 0  # of which the generic program drew (pathtrace.device.programs)
        self.aovs = aovs          # whether the denoiser's albedo and normal are accumulated too
        self._aov_kernel = None   # their kernel, once a pass has drawn them (aux_kernel)
        self.resets = 0           # how many times the image restarted (pathtrace.rendering.launches.Progressive)
        self._stale = False       # whether the images hold what a reset discarded (_clear_stale)
        self.traversal_stats = 0  # Features.traversal_stats: set through count_traversal()
        self.divergence_stats = 0 # Features.divergence_stats: set through record_shading(),
        self.shading_records = None   # with the buffer the launches record into
        self.pass_records = None      # and those of the passes of continue_paths
        self.set_scene(scene, progress, settings)
        self.resize(width or self.settings.width, height or self.settings.height)

    # --- what is rendered ------------------------------------------------------------------
    def set_scene(self, scene, progress=None, settings=None):
        """Uploads a compiled scene (compiling a Scene first, on this device); takes its camera and
        settings (or `settings`); resets. Where the scene's tree is not built yet
        (compile_scene(tree=False)), the scene's own program, if it is to be built, builds beside
        it (start_program), and so does the AOVs' where they are on (aux_kernel)."""
        self.compiled = scene if isinstance(scene, CompiledScene) \
            else compile_scene(scene, self.backend.queue, progress, tree=False)
        self.scene: Scene = self.compiled.scene
        self.camera = self.scene.camera.copy()
        self.settings = settings if settings is not None else self.scene.settings
        self.auto_plan, self.plan_seconds, self.plan_cached = None, {}, False  # "auto" chooses again
        with _LIGHT_SAMPLER_LOCK:    # a device group's renderers share the scene, made at once
            if self.compiled.light_sampler != self._light_sampler():
                self.compiled.light_sampler = self._light_sampler()
                if self.compiled.tree_ended is not None:     # given whole: its light table again
                    self.compiled.compile_lights()
        self.compiled.check_memory(self.backend.device.device)
        self.start_program()
        if self.aovs and self.settings.integrator == "path":    # (BDPT's features need the tree)
            self.aux_kernel("render_aovs", start_only=True)
        self.compiled.build_tree(self.backend.queue, when_bvh_built=self.compile_ahead())
        self._select_program()
        self._size_queue()
        for name, array in self.compiled.geometry_arrays().items():
            self._upload(name, array)
        self._upload_environment()
        self._upload_materials()
        self.reset()

    @property
    def bvh_seconds(self) -> float:
        return self.compiled.bvh_seconds

    @property
    def environment(self) -> Environment:
        return self.scene.environment

    @property
    def lights(self):
        return self.compiled.lights

    def upload_materials(self):
        """Uploads the scene's material table and the light table after an edit; resets."""
        self.compiled.update_materials()
        self._select_program()
        self._upload_materials()
        self.reset()

    def set_environment(self, environment: Environment):
        self.scene.environment = environment
        self.compiled.update_materials()
        self._upload_environment()
        self._upload_materials()
        self.reset()

    def _upload_environment(self):
        self._upload("env", self.environment.rgba())
        marginal, conditional = self.environment.sampling_cdfs()
        self._upload("env_marginal", marginal)
        self._upload("env_conditional", conditional)

    def _upload_materials(self):
        for name, array in self.compiled.material_arrays().items():
            self._upload(name, array)

    def _nearest_hit(self, origin, direction) -> tuple:
        """(primitive, distance) of the nearest hit along a ray; primitive -1 where there is none."""
        out = cl.Buffer(self.backend.context, cl.mem_flags.WRITE_ONLY, 8)
        kernel = self.aux_kernel("pick")
        kernel(self.backend.queue, (1,), None, *self.scene_args(),
               np.int32(self.compiled.num_spheres), np.int32(self.compiled.layout), np.append(np.float32(origin), 0).astype(np.float32),
               np.append(np.float32(direction), 0).astype(np.float32), out)
        hit = np.zeros(2, np.int32)
        cl.enqueue_copy(self.backend.queue, hit, out)
        return int(hit[0]), float(hit[1:].view(np.float32)[0])

    def pick(self, origin, direction):
        """The shape seen along a ray (a ShapeRef), or None."""
        prim, _ = self._nearest_hit(origin, direction)
        return self.compiled.shape(prim) if prim >= 0 else None

    def hit_distance(self, origin, direction):
        """The distance along a ray (of unit direction) to the first surface, or None."""
        prim, t = self._nearest_hit(origin, direction)
        return t if prim >= 0 else None

    def scene_args(self) -> tuple:
        """The scene's device buffers in the order of the kernels' SCENE_KERNEL_ARGS
        (kernels/scene.cl), for kernels beside the renderer's (app/bench/trace_split.py)."""
        return tuple(self._buffers[name] for name in SCENE_BUFFERS)

    def set_camera(self, camera: Camera):
        self.camera = camera.copy()
        self._select_program()
        self.reset()

    def set_settings(self, **changes):
        if "path_queue" in changes:
            self.auto_plan, self.plan_seconds, self.plan_cached = None, {}, False  # "auto" chooses again
        self.settings = replace(self.settings, **changes)
        if self._light_sampler() != self.compiled.light_sampler:
            self.compiled.light_sampler = self._light_sampler()
            self.upload_materials()
        self._select_program()
        self._size_queue()
        self.reset()

    def _light_sampler(self) -> str:
        """How the compiled scene chooses lights: as the settings say, or for BDPT by power
        alone, which light subpaths start from (pbrt-v4's BDPT uses its power sampler too)."""
        return self.settings.light_sampler if self.settings.integrator == "path" else "power"

    def resize(self, width: int, height: int):
        if (width, height) == (self.width, self.height):
            return
        self._allocate_images(width, height, self.aovs)

    def set_aovs(self, on: bool):
        """Starts (or stops) accumulating the denoiser's albedo and normal beside the radiance;
        resets."""
        if on != self.aovs:
            self._allocate_images(self.width, self.height, on)
        if on:      # their program's build started, beside the scene's own, where it is due
            self.aux_kernel("render_aovs", start_only=True)

    def _allocate_images(self, width: int, height: int, aovs: bool):
        nbytes = width * height * 16
        images = image_buffers(aovs)
        queue = self._queue_buffers(width, height)
        others = {name: b.size for name, b in self._buffers.items()
                  if name not in image_buffers(True) and name not in queue}
        what = f"the {width}x{height} image of {self.scene.name}"
        check_fits(self.backend.device.device, {**others, **{name: nbytes for name in images}, **queue}, what)
        host = READ_BACK_BYTES * width * height
        if self.backend.device.device.host_unified_memory:    # a CPU device's buffers are the host's
            host += nbytes * len(images)
        available = available_host_memory()
        if available is not None and host > available:
            raise UserError(f"{what} needs about {format_bytes(host)} of memory to render, read back "
                            f"and write; {format_bytes(available)} is available")
        self.width, self.height, self.aovs = width, height, aovs
        for name in (*AOV_BUFFERS, "splats", *PHOTON_BUFFERS):
            self._buffers.pop(name, None)
        for name in images:
            self._buffers[name] = cl.Buffer(self.backend.context, cl.mem_flags.READ_WRITE, nbytes)
        self._place_queue(queue)
        self.reset()

    def _queue_buffers(self, width: int, height: int) -> dict:
        """The bytes of each of the continuation queue's buffers, for the launch plan and image
        size: scratch of each launch, which no image keeps between launches."""
        capacity = max(self.queue_capacity(width, height), 1)       # (a buffer has bytes)
        entries = PATH_RECORD.itemsize * capacity
        results = width * height * self.queue_samples(width, height) if self.queue_plan()[1] else 1
        passes = self.queue_passes()
        queue = {"queue": entries, "queue_next": entries, "counters": 4 * (passes + 2), "results": 16 * results}
        sort = self.sorts_queue()
        queue.update({name: 4 * (capacity if sort else 1) for name in SORT_BUFFERS})
        queue.update(key_counts=4 * ((passes + 1) * self.sort_keys() if sort else 1),
                     offsets=4 * (self.sort_keys() if sort else 1))
        return queue

    def _place_queue(self, queue: dict, check: bool = False):
        """The queue's buffers of `queue`'s sizes; `check`: first against the device's memory
        with the other buffers as they are (a change of plan, the image kept)."""
        if check:
            others = {name: b.size for name, b in self._buffers.items() if name not in queue}
            check_fits(self.backend.device.device, {**others, **queue},
                       f"the {self.width}x{self.height} image of {self.scene.name}")
        for name, size in queue.items():
            self._buffers[name] = cl.Buffer(self.backend.context, cl.mem_flags.READ_WRITE, size)
        self._queued_for = (self.queue_plan()[1], self.sorts_queue(), self.queue_passes())

    def queue_passes(self) -> int:
        """The passes of continue_paths that trace one vertex each, before the last, which traces
        the paths to their ends: QUEUE_PASSES; with path_sort, one for every vertex its paths can
        shade past the render launch's and before max_depth (at most SORT_PASSES), since a pass
        sorts its paths by their first ray alone, and the warps of the last pass diverge again
        after it (kernels/path_sort.cl)."""
        if not self.sorts_queue():
            return QUEUE_PASSES
        depth = self.settings.max_depth
        return max(1, min(SORT_PASSES, depth - self.queue_plan()[0] - 1 if depth > 0 else SORT_PASSES))

    def queue_samples(self, width: int, height: int) -> int:
        """Samples per pixel of a launch with the continuation queue."""
        return max(1, min(MAX_LAUNCH_SAMPLES, QUEUE_POOL // (width * height)))

    def queue_capacity(self, width: int, height: int) -> int:
        """Entries of the continuation queue for a width x height image (0 where launches do
        not use it)."""
        if not self.queue_plan()[1]:
            return 0
        memory = self.backend.device.device.global_mem_size // 16 // PATH_RECORD.itemsize
        return min(width * height * self.queue_samples(width, height), MAX_QUEUED, memory)

    def reset(self):
        """Restarts the progressive average; the images are cleared before their next use."""
        self._stale = True
        self.samples = self.generic_samples = 0
        self.resets += 1

    def _clear_stale(self):
        """Clears the images where a reset left them to clear: once for resets in a row, at the
        size that is then used. A viewer's renderer made at the scene's size and resized to its
        first preview had cleared four images of 33 MB, 65 ms on two cores, before its first
        launch."""
        if self._stale and "sum" in self._buffers:
            for name in image_buffers(self.aovs):
                cl.enqueue_fill_buffer(self.backend.queue, self._buffers[name], np.float32(0), 0,
                                       self.width * self.height * 16)
            self._stale = False

    # --- rendering -------------------------------------------------------------------------
    def params(self, sample_count: int) -> np.ndarray:
        p = np.zeros((), RENDER_PARAMS)
        self.camera.pack(p, self.width / self.height)
        p["filter"] = self.settings.filter.params()
        p["env_scale"][:3] = self.environment.intensity
        p["world"] = (*self.compiled.center, self.compiled.radius)
        p["width"], p["height"] = self.width, self.height
        p["sample_start"], p["sample_count"] = self.samples, sample_count
        p["seed"] = self.settings.seed
        p["max_depth"] = self.settings.max_depth
        h, w, _ = self.environment.image.shape
        p["env_width"], p["env_height"] = w, h
        p["env_frame"][:, :3] = self.environment.map_from_world()
        p["env_row_scale"], p["env_row_offset"] = self.environment.row_mapping()
        p["num_lights"] = self.lights.count
        p["env_pick"] = self.lights.env_pick
        p["num_spheres"] = self.compiled.num_spheres
        p["rr_depth"] = RR_DEPTH
        p["camera_medium"] = self.scene.camera_medium
        p["camera_type"] = CAMERA_KERNELS.index(self.camera.kernel)
        p["filter_type"] = FILTERS.index(self.settings.filter.name)
        p["rr_rule"] = RUSSIAN_ROULETTE.index(self.settings.russian_roulette)
        p["layout"] = self.compiled.layout
        return p

    def add_samples(self, count: int = 1, start: int = None, rows: tuple = None) -> list:
        """Queues the launches that add `count` samples to every pixel (one per
        MAX_LAUNCH_SAMPLES, and one for the albedo and normal over the first AOV_PASSES samples,
        with set_aovs); returns their events. The
        samples are those of index start, start + 1, ... (default: the next ones of this
        renderer), so that several renderers can share one render's sample indices.

        rows = (first, end) adds them to those rows only: a band of a pass, so that no launch
        holds a window up (pathtrace.rendering.launches.Progressive). Bands go top to bottom; `samples` counts
        whole passes, so it grows with the band that ends at the last row. A pass split into
        bands adds the very samples one launch would."""
        self.switch_when_built()
        self._clear_stale()
        b = self._buffers
        first, end = rows if rows is not None else (0, self.height)
        start = self.samples if start is None else start
        global_size, local = self.launch_grid(end - first)
        params = self.params(count)
        params["row_start"], params["row_end"], params["sample_start"] = first, end, start
        add = self._add_bidirectional if self.bdpt_kernels is not None else self._add_paths
        events = add(params, count, start, global_size, local)
        if self.aovs and self.samples < AOV_PASSES:
            if self._aov_kernel is None:     # (its program was started by set_aovs)
                self._aov_kernel = self.aux_kernel("render_aovs")
            self._aov_kernel.set_args(*self.scene_args(), params, b["albedo_sum"], b["normal_sum"])
            events.append(cl.enqueue_nd_range_kernel(self.backend.queue, self._aov_kernel, global_size, local))
        if end >= self.height:
            self.samples += count
            self._build_due = True
            self.generic_samples += count if self.uses_generic_program else 0
        return events

    def launch_grid(self, rows: int) -> tuple:
        """(global size, local size) of the render launches over `rows` rows: a work-item per
        pixel, in groups of PIXEL_GROUP, the image padded to whole groups."""
        return tuple(-(-n // l) * l for n, l in zip((self.width, rows), PIXEL_GROUP)), PIXEL_GROUP

    def _add_paths(self, params, count: int, start: int, global_size: tuple, local: tuple) -> list:
        """Queues the path tracer's launches that add `count` samples to the rows of `params`
        (with the continuation queue where the plan uses it); returns their events."""
        b = self._buffers
        kernel = self.kernels[self.settings.nee]
        events = []
        sums = tuple(b[name] for name in SUM_BUFFERS)
        capacity = np.int32(self.queue_capacity(self.width, self.height))
        # with the continuation queue, a few samples per launch (queue_samples), for which the
        # launch's pixels have room in `results` (kernels/integrator.cl: render_pixel)
        queued = self.queue_plan()[1] and self.continue_kernels is not None
        step = self.queue_samples(self.width, self.height) if queued else MAX_LAUNCH_SAMPLES
        for offset in range(0, count, step):
            launch = params.copy()
            launch["sample_start"], launch["sample_count"] = start + offset, min(step, count - offset)
            if queued:
                for name in ("counters", "key_counts") if self.sort_kernels else ("counters",):
                    events.append(cl.enqueue_fill_buffer(self.backend.queue, b[name], np.int32(0), 0, b[name].size))
            records = (self.shading_records,) if self.divergence_stats else ()   # (kernels/divergence.cl)
            sort = (b["keys"], b["key_counts"], np.int32(self.sort_keys()), np.int32(self.sort_shift())) \
                if self.sort_kernels else ()
            kernel.set_args(*self.scene_args(), launch, *sums, b["queue"], b["counters"], capacity, b["results"],
                            *sort, *records)
            events.append(cl.enqueue_nd_range_kernel(self.backend.queue, kernel, global_size, local))
            if queued:
                events += self._continue_paths(launch, capacity, global_size)
        return events

    def _add_bidirectional(self, params, count: int, start: int, global_size: tuple, local: tuple) -> list:
        """Queues the launches of render_bdpt (kernels/bdpt.cl) that add `count` samples to the
        rows of `params`, one sample a launch (with caustic photons, after its photon pass:
        app/rendering/photons.py), each followed by add_splats over the whole image, which adds
        the light tracing's splats (they land anywhere in the image) to the sums. Returns their
        events. One sample a launch: on an H200 a launch of 64 samples a work-item took 3.1-3.7x
        the time per sample of 64 launches of one; on PoCL they are level
        (docs/notes/performance-2026-11.md, 2026-11-30)."""
        b = self._buffers
        if "splats" not in b:
            b["splats"] = cl.Buffer(self.backend.context, cl.mem_flags.READ_WRITE, self.width * self.height * 16)
            cl.enqueue_fill_buffer(self.backend.queue, b["splats"], np.float32(0), 0, self.width * self.height * 16)
        render, add = self.bdpt_kernels
        whole = tuple(-(-n // l) * l for n, l in zip((self.width, self.height), local))
        events = []
        for offset in range(count):
            launch = params.copy()
            launch["sample_start"], launch["sample_count"] = start + offset, 1
            photons = ()
            if self.uses_photons():
                passed, photons = self._photon_pass(launch, whole, local)
                events += passed
            render.set_args(*self.scene_args(), launch, *(b[name] for name in SUM_BUFFERS), b["splats"], *photons)
            events.append(cl.enqueue_nd_range_kernel(self.backend.queue, render, global_size, local))
            add.set_args(launch, b["sum"], b["sum_c"], b["splats"])
            events.append(cl.enqueue_nd_range_kernel(self.backend.queue, add, whole, local))
        return events

    def _continue_paths(self, launch, capacity, global_size) -> list:
        """Queues the passes of continue_paths over the paths that the render launch `launch`
        queued, each taking them from one of the two queues and queueing those that go on in the
        other, then add_queued_paths; returns their events."""
        b, events = self._buffers, []
        queues, keys = (b["queue"], b["queue_next"]), (b["keys"], b["keys_next"])
        follow = self.continue_kernels[self.settings.nee]
        size = (self.queue_launch_size(launch, capacity),)
        passes = self.queue_passes()
        for k in range(passes + 1):
            steps = 1 if k < passes else 0
            sort = ()
            if self.sort_kernels:
                events += self._sort_queue(k, keys[k % 2], capacity, size, (QUEUE_GROUP,))
                sort = (b["order"], keys[(k + 1) % 2], b["key_counts"], np.int32(self.sort_keys()),
                        np.int32(self.sort_shift()))
            records = (self.pass_records[k],) if self.divergence_stats else ()   # (kernels/divergence.cl)
            follow.set_args(*self.scene_args(), launch, queues[k % 2], queues[(k + 1) % 2], b["counters"],
                            np.int32(k), capacity, np.int32(steps), b["results"], *sort, *records)
            events.append(cl.enqueue_nd_range_kernel(self.backend.queue, follow, size, (QUEUE_GROUP,)))
        self.add_queued.set_args(launch, *(b[name] for name in SUM_BUFFERS), b["results"])
        events.append(cl.enqueue_nd_range_kernel(self.backend.queue, self.add_queued, global_size, (8, 8)))
        return events

    def queue_launch_size(self, launch, capacity) -> int:
        """The work-items of each pass of continue_paths after render launch `launch`: one per path
        it could have queued, in whole work-groups."""
        rows = int(launch["row_end"] - launch["row_start"])
        paths = min(int(capacity), self.width * rows * int(launch["sample_count"]))   # at most one a sample
        return -(-paths // QUEUE_GROUP) * QUEUE_GROUP

    def finish(self):
        """Waits for the work queued to end, the clearing of the images a reset left among it
        (so that a timed launch after reset() and finish() does not clear them)."""
        self._clear_stale()
        self.backend.queue.finish()

    def buffer(self, name: str) -> cl.Buffer:
        """One of the device buffers of image_buffers, for kernels beside the renderer's."""
        self._clear_stale()
        return self._buffers[name]

    def _read(self, name) -> np.ndarray:
        self._clear_stale()
        out = np.empty((self.height, self.width, 4), np.float32)
        cl.enqueue_copy(self.backend.queue, out, self._buffers[name])
        return out

    def _read_compensated(self, name) -> np.ndarray:
        """A compensated sum (kernels/integrator.cl add_compensated) as float64: sum - c."""
        return self._read(name).astype(np.float64) - self._read(f"{name}_c")

    def read_sum(self) -> np.ndarray:
        """The radiance sums, (H, W, 4) float32: rgb, and the samples kept in a (within an ulp
        of the compensated sums: exact counts come from dropped_samples)."""
        return self._read("sum")

    def mean(self) -> np.ndarray:
        """The image so far: mean radiance per pixel, (H, W, 3) float32."""
        return self._read("sum")[..., :3] / max(self.samples, 1)

    def read_aovs(self) -> dict:
        """The auxiliary images so far (set_aovs): "albedo", the mean albedo clamped to [0, 1],
        and "normal", the mean shading normal (not renormalised; 0 where paths escaped), each
        (H, W, 3) float32; "depth", the mean distance from the camera to the first surface
        (0 where the camera ray escaped), (H, W) float32."""
        return aov_means(self.read_albedo_sum(), self.read_normal_sum())

    def read_albedo_sum(self) -> np.ndarray:
        """The raw albedo sums (set_aovs), (H, W, 4) float32: rgb, and the samples in w."""
        return self._read("albedo_sum")

    def read_normal_sum(self) -> np.ndarray:
        """The raw normal sums (set_aovs), (H, W, 4) float32: xyz, and the depths in w."""
        return self._read("normal_sum")

    def read_async(self, names: tuple) -> tuple:
        """Queues copies of the named buffers (of image_buffers) to new host arrays without
        waiting; returns (the last copy's event, the arrays)."""
        self._clear_stale()
        arrays = [np.empty((self.height, self.width, 4), np.float32) for _ in names]
        events = [cl.enqueue_copy(self.backend.queue, a, self._buffers[n], is_blocking=False)
                  for a, n in zip(arrays, names)]
        self.backend.queue.flush()
        return events[-1], arrays

    def dropped_samples(self) -> int:
        """Samples left out since the last reset because they were NaN or infinite
        (kernels/integrator.cl counts the kept ones), all pixels together."""
        return self.samples * self.width * self.height - int(round(self._read_compensated("sum")[..., 3].sum()))

    def count_traversal(self, kind: int):
        """From now on, rays_traced() counts nodes visited (kind 1) or primitives tested (2) in
        the BVH instead of rays (0: rays again); resets."""
        self.traversal_stats = kind
        self._select_program()
        self.reset()

    def record_shading(self, records: cl.Buffer, iterations: int, pass_records: tuple = None):
        """From now on, the path tracer's launches record the shading of the first `iterations`
        iterations of each path into `records` (app/bench/divergence_stats.py, kernels/divergence.cl:
        one byte per sample of the launch, iteration, field and work-item of launch_grid), and
        where launches use the continuation queue, pass k of continue_paths into pass_records[k]
        (the same as one sample, its work-items those of queue_launch_size); `iterations` 0: no
        more. Resets."""
        self.divergence_stats, self.shading_records = iterations, records if iterations else None
        self.pass_records = pass_records if iterations else None
        self._select_program()
        self._size_queue()
        self.reset()

    def rays_traced(self) -> int:
        """Rays traced since the last reset (camera rays and bounces), all pixels together."""
        return int(round(self._read_compensated("sum_sq")[..., 3].sum()))

    def read_sum_sq(self) -> np.ndarray:
        """The sums of squares, (H, W, 4) float32: rgb, and rays traced in a."""
        return self._read("sum_sq")

    def variance(self) -> np.ndarray:
        """The per-sample variance of each pixel and channel (of one sample, not of the mean). With
        bdpt or ptracer, of the camera subpaths' part alone: light tracing's splats land in other
        pixels' sums, not one sample's (kernels/bdpt.cl: add_splats)."""
        return variance_of(self.read_sum(), self.read_sum_sq(), self.samples)

    def _upload(self, name, array):
        array = np.ascontiguousarray(array)
        if array.size == 0:       # OpenCL has no empty buffers; the kernels never read this one
            array = np.zeros(1, array.dtype)
        self._buffers[name] = cl.Buffer(self.backend.context,
                                        cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR,
                                        hostbuf=array)
