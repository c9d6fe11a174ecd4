"""What a command shows on standard error while it works: a BVH build's progress bar and the
lines of `render`'s phases with their times."""

import sys
import time

PROGRESS_AFTER = 1.0    # seconds before a BVH build shows its progress
LOG_INTERVAL = 10.0     # seconds between a bar's redraws where standard error is not a terminal


def redraw_interval() -> float:
    """tqdm's mininterval for a bar on standard error: its own 0.1 s on a terminal; in a file or
    a pipe (a log), whose redraws all pile up in it, one every LOG_INTERVAL (the first and the
    last are drawn whatever the interval)."""
    try:
        return 0.1 if sys.stderr.isatty() else LOG_INTERVAL
    except (AttributeError, ValueError):       # no standard error, or a closed one
        return LOG_INTERVAL


class BuildProgress:
    """A progress bar for a scene's BVH build on standard error, shown once the build has taken
    PROGRESS_AFTER seconds; call it with the fraction done."""

    def __init__(self, name: str, quiet: bool):
        from tqdm import tqdm
        self.bar = tqdm(total=100, desc=f"{name}: building the BVH", unit="%", delay=PROGRESS_AFTER,
                        file=sys.stderr, disable=quiet, mininterval=redraw_interval(),
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}")

    def __call__(self, fraction: float):
        self.bar.update(100 * fraction - self.bar.n)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        self.bar.close()


class Phases:
    """The lines of `render`'s phases on standard error, each with its time: called with what
    was done as each phase ends, it prints "WHAT in SECONDS s" (nothing when quiet). A phase's
    time runs from the end of the one before (or from restart()); one timed elsewhere gives its
    `seconds`."""

    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.restart()

    def restart(self):
        """Times the next phase from now."""
        self.start = time.perf_counter()

    def __call__(self, what: str, note: str = "", seconds: float = None):
        if seconds is None:
            seconds = time.perf_counter() - self.start
        if not self.quiet:
            print(f"{what} in {seconds:.2f} s{note}", file=sys.stderr)
        self.restart()
