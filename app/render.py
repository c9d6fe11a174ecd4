"""Rendering in launches sized to a time budget: progress stays smooth, a window stays
responsive, and no launch runs long enough for an OS GPU watchdog (a few seconds) to stop it."""

import time

from app.renderer import Renderer


def next_launch_size(count: int, elapsed: float, target_seconds: float) -> int:
    """Samples per pixel for the next launch, given that `count` took `elapsed` seconds:
    towards `target_seconds`, growing at most 4x at a time (the first launches are small)."""
    per_sample = max(elapsed / count, 1e-9)
    return max(1, min(int(target_seconds / per_sample), 4 * count))


def render_samples(renderer: Renderer, spp: int, on_progress=None, launch_seconds: float = 0.25):
    """Adds `spp` samples per pixel; on_progress(samples_done) after each launch."""
    chunk = 1
    while renderer.samples < spp:
        count = min(chunk, spp - renderer.samples)
        start = time.perf_counter()
        renderer.add_samples(count)
        renderer.finish()
        if on_progress:
            on_progress(renderer.samples)
        chunk = next_launch_size(count, time.perf_counter() - start, launch_seconds)
