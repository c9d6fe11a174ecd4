"""The launch plans of `path_queue = "auto"`: which of three ways to launch a scene's paths a
GPU renders it fastest with, chosen by trial renders before a render and remembered on disk
(docs/performance.md). A part of the Renderer (app/rendering/renderer.py), which is one."""

import hashlib
import json
import time
from dataclasses import replace
from pathlib import Path

import pyopencl as cl

from pathtrace.device.occupancy import TUNING_RULE
from pathtrace.io.cache_files import cache_dir
from pathtrace.errors import UserError
from pathtrace.io.cache_files import read_entry, write_entry
from pathtrace.rendering.choices import PATH_QUEUE_AUTO

# The launch plans that path_queue "auto" chooses among on a GPU, as (the queue depth the program
# is built with, whether launches use the queue): no queue; the queue after the first vertex; and
# the queue's program with its queue unused. The three trace the same rays into the same image,
# but NVIDIA's compiler schedules the queue's program differently, and which of the three is
# fastest depends on the scene as much as on the paths (docs/notes/performance-2026-11.md, 2026-11-27: the
# queue chosen by trial renders).
AUTO_PLANS = ((0, False), (1, True), (1, False))
PLAN_NAMES = dict(zip(AUTO_PLANS, ("no queue", "queue", "queue unused")))
TRIAL_SAMPLES = 16        # samples per pixel of each trial render of a plan (two rounds of trials)
TRIALS_SPP = 2 * len(AUTO_PLANS) * TRIAL_SAMPLES     # what the trials draw in all


class QueuePlans:
    """The Renderer's choice of launch plan (its state is set in Renderer.__init__)."""

    def _size_queue(self):
        """After a change of settings or plan: the continuation queue's buffers sized for whether
        launches use it and sort it, and for its passes (which queue depth does not change); the
        image is kept (path_queue "auto" keeps its trials' samples)."""
        if self.width and self._queued_for != (self.queue_plan()[1], self.sorts_queue(), self.queue_passes()):
            self._place_queue(self._queue_buffers(self.width, self.height), check=True)

    def queue_plan(self) -> tuple:
        """(the queue depth the program is built with, whether launches use the queue): from
        settings.path_queue, or with "auto" the plan its trials chose (no queue until then)."""
        if self.settings.integrator != "path":
            return AUTO_PLANS[0]       # BDPT has no queue
        if self.settings.path_queue == PATH_QUEUE_AUTO:
            return self.auto_plan or AUTO_PLANS[0]
        return self.settings.path_queue, self.settings.path_queue > 0

    def choose_queue_plan(self, samples: int, trials: bool = None, first: int = None):
        """With path_queue "auto", before a render of `samples` samples per pixel: renders
        TRIAL_SAMPLES samples per pixel with each of AUTO_PLANS, twice in turn, and keeps the
        plan of the fastest trial (their seconds in plan_seconds). Then resets, unless `first`
        is given: then the trials draw the sample indices first, first + 1, ... and their
        samples stay in the image, which a render goes on from (the plans render the same
        samples, to float rounding), rather than costing the render TRIALS_SPP samples more. The
        plans' programs are built here, before the trials time anything; a plan whose queue does
        not fit in the device's memory is left out. `trials` (default: on GPUs only): on other
        devices, whose work-items run one after another, the queue only costs
        (docs/performance.md), so they take no queue without trials; so does a render shorter
        than the trials."""
        if self.settings.path_queue != PATH_QUEUE_AUTO or self.auto_plan is not None:
            return
        if trials is None:
            trials = bool(self.backend.device.device.type & cl.device_type.GPU)
        if not trials or samples < TRIALS_SPP:
            self.use_queue_plan(AUTO_PLANS[0])
            return
        verdict = self._plan_verdict_path()
        cached = read_entry(verdict)
        if cached is not None and tuple(json.loads(bytes(cached))) in AUTO_PLANS:
            self.plan_seconds = {}
            self.use_queue_plan(tuple(json.loads(bytes(cached))))
            self.plan_cached = True
            return
        seconds, drawn = {}, 0
        for _ in range(2):
            for plan in AUTO_PLANS:
                try:
                    self.use_queue_plan(plan)
                except UserError:      # its queue does not fit in the device's memory: no candidate
                    continue
                self.switch_when_built(wait=True)      # trials time the plans' own programs
                if first is None:
                    self.reset()
                self.finish()
                start = time.perf_counter()
                self.add_samples(TRIAL_SAMPLES, None if first is None else first + drawn)
                self.finish()
                drawn += TRIAL_SAMPLES
                seconds[plan] = min(seconds.get(plan, float("inf")), time.perf_counter() - start)
        self.plan_seconds = seconds
        self.use_queue_plan(min(seconds, key=seconds.get))
        write_entry(verdict, json.dumps(self.auto_plan).encode())
        if first is None:
            self.reset()

    def _plan_verdict_path(self) -> Path:
        """Where the trials' verdict for this scene's program, image size and device is kept, so
        that they run once, not before every render (pathtrace.io.cache_files). With path_sort
        the queue's plan is the sorted queue's, whose verdict is kept apart."""
        d = self.backend.device.device
        features = replace(self.compiled.features(self.settings, self.camera), path_queue=0,
                           path_sort=bool(self.settings.path_sort))
        key = hashlib.sha256("\0".join(map(str, (
            features, self.width, self.height, AUTO_PLANS, TRIAL_SAMPLES, TUNING_RULE,
            d.platform.name, d.platform.version, d.name, d.version, d.driver_version))).encode()).hexdigest()[:32]
        return cache_dir() / "queue-plans" / f"{key}.bin"

    def describe_queue_plan(self) -> str:
        """The plan path_queue "auto" chose (choose_queue_plan), in words, with each plan's fastest
        trial where it ran trials."""
        trials = ", ".join(f"{PLAN_NAMES[p]} {s:.4f} s" for p, s in self.plan_seconds.items())
        words = PLAN_NAMES[self.auto_plan]
        if self.plan_cached:
            return f"{words} (as earlier trials chose)"
        return f"{words} (trials of {TRIAL_SAMPLES} spp: {trials})" if trials else words

    def use_queue_plan(self, plan: tuple):
        """Renders with `plan` (one of AUTO_PLANS) from now on, as path_queue "auto" would once
        its trials chose it."""
        self.auto_plan = plan
        self._select_program()
        self._size_queue()
