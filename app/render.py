"""Rendering a still: samples added in launches sized to take about `launch_seconds` each, which
keeps progress smooth and every launch far below an OS GPU watchdog's limit."""

import time

from app.renderer import Renderer


def render_samples(renderer: Renderer, spp: int, on_progress=None, launch_seconds: float = 0.25):
    """Adds `spp` samples per pixel; on_progress(samples_done) after each launch."""
    chunk = 1
    while renderer.samples < spp:
        count = min(chunk, spp - renderer.samples)
        start = time.perf_counter()
        renderer.add_samples(count)
        renderer.finish()
        elapsed = time.perf_counter() - start
        if on_progress:
            on_progress(renderer.samples)
        # grow or shrink the next launch towards the target duration, at most 4x at a time
        per_sample = max(elapsed / count, 1e-9)
        chunk = max(1, min(int(launch_seconds / per_sample), 4 * count))
