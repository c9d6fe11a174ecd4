"""Rendering in launches sized to a time budget: progress stays smooth, a window stays
responsive, and no launch runs long enough for an OS GPU watchdog (a few seconds) to stop it."""

import time



def next_launch_size(count: int, elapsed: float, target_seconds: float) -> int:
    """Samples per pixel for the next launch, given that `count` took `elapsed` seconds:
    towards `target_seconds`, growing at most 4x at a time (the first launches are small)."""
    per_sample = max(elapsed / count, 1e-9)
    return max(1, min(int(target_seconds / per_sample), 4 * count))
