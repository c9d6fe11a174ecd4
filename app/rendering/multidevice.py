"""One render on several devices. The scene is compiled once and uploaded to each device; every
device adds whole-image samples to its own accumulation buffers, drawing sample indices from one
shared counter, and the sums are added at the end. The random numbers of a sample are keyed on
its absolute index (kernels/rng.cl), so the image does not depend on which device rendered which
sample: it equals a one-device render of the same samples up to the order of float additions.

Balancing follows the idea of Cycles' work balancer: each device takes launches sized to its own
measured speed (pathtrace.rendering.launches.next_launch_size), so a fast device takes more samples and a device
that slows down takes fewer; near the end a device takes no more than its share of what is left,
by the measured speeds and the launches the others have yet to finish, so that all end together
and none is left finishing a long launch alone."""

import math
import threading
import time

import numpy as np

from pathtrace.compiler.compiled import CompiledScene, compile_scene
from pathtrace.device.opencl import Backend
from pathtrace.errors import UserError
from pathtrace.rendering.launches import next_launch_size
from pathtrace.rendering.queue_plans import TRIALS_SPP
from pathtrace.rendering.renderer import Renderer, aov_means, variance_of


FIRST_BANDS = 16       # the first sample of a render is split into this many launches of rows,
                       # until its speed is known: a 4096x4096 sample on two cores takes seconds


def row_bands(height: int, bands: int):
    """(first, end) of `bands` bands of rows covering [0, height), top to bottom."""
    edges = np.linspace(0, height, min(bands, height) + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]


class SampleCounter:
    """Hands out consecutive ranges of sample indices, [start, total), to several takers."""

    def __init__(self, total: int, start: int = 0):
        self.total = total
        self.issued = start
        self.stopped = False
        self._lock = threading.Lock()
        self._rates = {}        # taker -> its last measured samples per second
        self._busy_until = {}   # taker -> when the launch it took last should end (perf_counter)

    def take(self, taker, wanted: int, rate: float = None, now: float = None):
        """Up to `wanted` sample indices for `taker` (rate: its speed, samples/s), as
        (start, count), or None when all are issued or the render was stopped. Near the end a
        taker gets its share of what is left: with every taker of a known speed busy until
        the ends of the launches it took, and then working on what is left, all would end at
        one time T, and this taker's share is what it draws by then (`now`: the time,
        perf_counter's unless given)."""
        with self._lock:
            now = time.perf_counter() if now is None else now
            if rate:
                self._rates[taker] = rate
            left = self.total - self.issued
            if self.stopped or left <= 0:
                return None
            count = min(wanted, left)
            if rate and len(self._rates) > 1:
                others = [(r, max(self._busy_until.get(t, now) - now, 0.0))
                          for t, r in self._rates.items() if t != taker]
                seconds = (left + sum(r * busy for r, busy in others)) / sum(self._rates.values())
                count = max(1, min(count, math.ceil(rate * seconds)))
            if rate:
                self._busy_until[taker] = now + count / rate
            start = self.issued
            self.issued += count
            return start, count

    def stop(self):
        with self._lock:
            self.stopped = True


class DeviceGroup:
    """Renderers of one compiled scene on several backends, driven together."""

    def __init__(self, backends: list[Backend], scene, width: int = None, height: int = None,
                 progress=None, settings=None, aovs: bool = False):
        """scene: a CompiledScene, or a Scene to compile on the first device (progress as for
        Renderer), whose tree the first renderer to ask builds (Renderer.set_scene); settings and
        aovs, the first render's, as Renderer takes them. The
        renderers are made at once, each in a thread: each device builds its program and takes
        its uploads beside the others."""
        compiled = scene if isinstance(scene, CompiledScene) \
            else compile_scene(scene, backends[0].queue, progress, tree=False)
        for b in backends:       # every device, before any of them allocates
            compiled.check_memory(b.device.device)
        self.renderers = _each(lambda b: Renderer(b, compiled, width, height, settings=settings, aovs=aovs), backends)
        self.compiled = compiled

    @property
    def samples(self) -> int:
        """Samples per pixel accumulated over all devices."""
        return sum(r.samples for r in self.renderers)

    @property
    def bvh_seconds(self) -> float:
        return self.compiled.bvh_seconds

    def choose_queue_plans(self, spp: int, keep_up_to: int = 0):
        """With path_queue "auto", before a render of `spp` samples per pixel: each device's
        launch plan, by its trial renders (Renderer.choose_queue_plan); until then, no queue.
        Where every device's trials together draw at most `keep_up_to` samples per pixel (the
        render's first image has that many), their samples are kept: each device's trials draw
        the indices after those already drawn, so that the render goes on from them."""
        keep = keep_up_to >= TRIALS_SPP * len(self.renderers)
        for r in self.renderers:
            r.choose_queue_plan(spp, first=self.samples if keep else None)

    def queue_plans(self) -> list:
        """What path_queue "auto" chose on each device, in words (empty where it was not asked
        for or has not chosen yet)."""
        return [r.describe_queue_plan() for r in self.renderers if r.auto_plan is not None]

    def programs_used(self) -> list:
        """Where the generic program drew samples, on each device, in words
        (Renderer.describe_programs)."""
        return [f"{r.backend.device.name}: {words}" for r in self.renderers if (words := r.describe_programs())]

    def render(self, spp: int, on_progress=None, launch_seconds: float = 0.25):
        """Brings every pixel to `spp` samples: adds samples self.samples .. spp-1, spread over
        the devices (so that a render can go on where the last one stopped); on_progress(samples
        done) after each launch. A launch is sized to take about launch_seconds: several samples
        where one is quick, one sample split into bands of rows where it is not (the first is,
        until its speed is known). Re-raises the first device error; Ctrl-C stops every device
        after its current launch or band."""
        counter = SampleCounter(spp, self.samples)
        errors = []
        progress_lock = threading.Lock()

        def work(renderer):
            try:
                chunk, rate, bands = 1, None, FIRST_BANDS
                while (taken := counter.take(renderer, chunk, rate)) is not None:
                    start, count = taken
                    began = time.perf_counter()
                    for rows in row_bands(renderer.height, bands):
                        if counter.stopped:          # Ctrl-C: stop between bands, not after
                            return                   # a whole image's sample
                        renderer.add_samples(count, start, rows)
                        renderer.finish()
                    elapsed = time.perf_counter() - began
                    rate = count / max(elapsed, 1e-9)
                    chunk = next_launch_size(count, elapsed, launch_seconds)
                    bands = max(1, math.ceil(elapsed / count / launch_seconds))
                    if on_progress:
                        with progress_lock:
                            on_progress(self.samples)
            except BaseException as e:      # a device error ends the render for all
                errors.append(e)
                counter.stop()

        threads = [threading.Thread(target=work, args=(r,), daemon=True) for r in self.renderers]
        for t in threads:
            t.start()
        try:
            for t in threads:
                while t.is_alive():
                    t.join(0.1)             # wakes for Ctrl-C, which only the main thread gets
        except KeyboardInterrupt:
            counter.stop()
            for t in threads:
                t.join()
            raise
        if errors:
            raise errors[0]

    def samples_per_device(self) -> list[int]:
        return [r.samples for r in self.renderers]

    def _merged(self, read, dtype=np.float64) -> np.ndarray:
        """The sum over devices of one of each renderer's buffers (read: Renderer.read_sum or
        read_sum_sq), in `dtype`; the devices read back at once."""
        first, *others = _each(read, self.renderers)
        total = first.astype(dtype, copy=False)
        for other in others:
            np.add(total, other, out=total)
        return total

    def set_aovs(self, on: bool):
        """Accumulate the denoiser's albedo and normal too (Renderer.set_aovs), on every device."""
        for r in self.renderers:
            r.set_aovs(on)

    def read_aovs(self) -> dict:
        """The albedo, normal and depth over all devices (Renderer.read_aovs)."""
        return aov_means(self._merged(Renderer.read_albedo_sum), self._merged(Renderer.read_normal_sum))

    def mean(self) -> np.ndarray:
        """The image so far. Refused where a pixel kept more samples than were drawn: no sound
        program does that, and one built wrongly for its device does (the generic program as
        NVIDIA's driver 580 built it with eval_leaf_texture called: docs/notes/performance-2026-11.md,
        2026-11-30), its radiance wrong too. One that keeps fewer is not told from one that drops NaN samples
        (dropped_samples)."""
        # in float32, as one device's (Renderer.mean): each device's sums are float32 already,
        # and a float64 copy of a 1080p image's is 66 MB more to write and read at every snapshot
        sums = self._merged(Renderer.read_sum, np.float32)
        kept = sums[..., 3]
        over = int((kept > self.samples + 0.5).sum())
        if over:
            raise UserError(f"{self.compiled.scene.name}: {over} pixels kept more samples than were drawn (up to "
                            f"{kept.max():.0f} of {self.samples}): the kernels were built wrongly for this device; "
                            "no image is given (pathtrace devices --check tests the generic kernels; "
                            "--program specialised avoids them)")
        return sums[..., :3] / np.float32(max(self.samples, 1))

    def variance(self) -> np.ndarray:
        return variance_of(self._merged(Renderer.read_sum), self._merged(Renderer.read_sum_sq), self.samples)

    def rays_traced(self) -> int:
        return int(self._merged(Renderer.read_sum_sq)[..., 3].sum())

    def dropped_samples(self) -> int:
        return sum(r.dropped_samples() for r in self.renderers)


def _each(call, items) -> list:
    """[call(item) for item in items], each in a thread of its own (one item: in this one). The
    first error raised, in time, is raised here once every call has ended; Ctrl-C is raised at
    once, the threads (daemons) left to end with the process rather than keep it waiting for a
    driver's build."""
    if len(items) == 1:
        return [call(items[0])]
    results, errors = [None] * len(items), []

    def run(k):
        try:
            results[k] = call(items[k])
        except BaseException as e:
            errors.append(e)
    threads = [threading.Thread(target=run, args=(k,), daemon=True) for k in range(len(items))]
    for t in threads:
        t.start()
    for t in threads:
        while t.is_alive():
            t.join(0.1)             # wakes for Ctrl-C, which only the main thread gets
    if errors:
        raise errors[0]
    return results
