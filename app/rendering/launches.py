"""Rendering in launches sized to a time budget: progress stays smooth, a window stays
responsive, and no launch runs long enough for an OS GPU watchdog (a few seconds) to stop it."""

from collections import deque

import pyopencl as cl

QUEUE_AHEAD = 3        # launches kept queued, so that the device never waits for the window
                       # (with two, PoCL idled between a window's turns)


def next_launch_size(count: int, elapsed: float, target_seconds: float) -> int:
    """Samples per pixel for the next launch, given that `count` took `elapsed` seconds:
    towards `target_seconds`, growing at most 4x at a time (the first launches are small)."""
    per_sample = max(elapsed / count, 1e-9)
    return max(1, min(int(target_seconds / per_sample), 4 * count))


def _device_seconds(first: cl.Event, last: cl.Event) -> float:
    """From the start of `first` to the end of `last` (profiling counters, in ns)."""
    return (last.profile.end - first.profile.start) * 1e-9


class Progressive:
    """Feeds a Renderer without ever waiting for it, as an interactive window needs. Each call of
    step() collects the launches that have finished and queues new ones, so that QUEUE_AHEAD are
    always queued; each is sized, from the measured device time of the last, to take about
    `budget` seconds. Where a whole pass at one sample per pixel takes longer, a pass is split
    into bands of rows (Renderer.add_samples' rows); where it takes less, a launch adds several
    samples to every pixel. A reset of the renderer restarts the pass."""

    def __init__(self, renderer, budget: float):
        self.renderer, self.budget = renderer, budget
        self.seconds_per_pixel = None   # device seconds per pixel and sample, as last measured
        self._recent = deque()          # (pixel samples, device seconds) of the launches of the last pass or more
        self._recent_pixels = self._recent_seconds = 0.0    # their sums
        self._queued = deque()          # (first event, last event, rows, spp, epoch)
        self.paused = False             # queue nothing new (the window's denoiser needs the CPU)
        self._restart()

    def _restart(self):
        """After the renderer was reset (its image cleared, resized, or given a new camera or
        scene): passes start again at row 0; launches still in flight belong to the old image
        and only teach us their speed."""
        self._epoch = self.renderer.resets
        self._next_row = 0              # where the next band starts
        self.passes_done = 0            # whole passes finished on the device
        self.rows_done = 0              # rows of the pass under way finished on the device

    @property
    def progress(self) -> float:
        """How far the pass under way is, in [0, 1)."""
        return self.rows_done / max(self.renderer.height, 1)

    @property
    def samples_per_second(self) -> float:
        """Pixel samples per device second over the launches of the last whole image's worth of
        samples (a band of sky rows alone renders many times as fast as one of the scene's), or
        0 before the first launch ends."""
        return self._recent_pixels / self._recent_seconds if self._recent else 0.0

    def step(self) -> bool:
        """Collects finished launches and queues new ones; never blocks. Returns whether any
        launch of the current image finished since the last call."""
        if self._epoch != self.renderer.resets:
            self._restart()
        finished = self._collect()
        while len(self._queued) < QUEUE_AHEAD and not self.paused:
            self._queue(*self._next_launch())
        self.renderer.backend.queue.flush()
        return finished

    def _collect(self) -> bool:
        finished = False
        while self._queued and self._queued[0][1].command_execution_status == cl.command_execution_status.COMPLETE:
            first, last, rows, spp, epoch = self._queued.popleft()
            pixels = (rows[1] - rows[0]) * self.renderer.width * spp
            seconds = max(_device_seconds(first, last), 1e-9)
            self.seconds_per_pixel = seconds / pixels
            self._recent.append((pixels, seconds))
            self._recent_pixels += pixels
            self._recent_seconds += seconds
            image = self.renderer.width * self.renderer.height
            while len(self._recent) > 1 and self._recent_pixels - self._recent[0][0] >= image:
                old_pixels, old_seconds = self._recent.popleft()
                self._recent_pixels -= old_pixels
                self._recent_seconds -= old_seconds
            if epoch == self._epoch:
                finished = True
                whole = rows[1] >= self.renderer.height
                self.rows_done = 0 if whole else rows[1]
                self.passes_done += spp if whole else 0
        return finished

    def _next_launch(self) -> tuple:
        """(rows, samples per pixel) of the next launch."""
        width, height = self.renderer.width, self.renderer.height
        if self.seconds_per_pixel is None:
            return max(height // 32, 1), 1              # a small first launch, to measure
        row_seconds = self.seconds_per_pixel * width
        if row_seconds * height < self.budget and self._next_row == 0:
            return height, max(1, int(self.budget / (row_seconds * height)))
        return max(1, int(self.budget / row_seconds)), 1

    def _queue(self, rows: int, spp: int):
        band = (self._next_row, min(self._next_row + rows, self.renderer.height))
        events = self.renderer.add_samples(spp, rows=band)
        self._queued.append((events[0], events[-1], band, spp, self._epoch))
        self._next_row = band[1] % self.renderer.height

    def finish_pass(self):
        """Queues the rest of the pass under way and waits for it, queueing nothing more: the
        renderer's image then holds exactly `samples` samples in every pixel (to read it, as a
        screenshot does)."""
        r = self.renderer
        if self._epoch == r.resets and self._next_row > 0:
            self._queue(r.height, 1)
        r.finish()
        self._collect()
