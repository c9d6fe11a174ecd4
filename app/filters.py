"""Pixel filters: where in and around its pixel each sample lands, by filter importance sampling
(kernels/camera.cl). Each type is a kernel file kernels/filters/<name>.cl, with Mitsuba 3's and
pbrt-v4's parameters: box (radius 0.5), tent (pbrt-v4's triangle; radius 1, pbrt-v4's 2) and
gaussian (stddev 0.5; radius 4 stddev, pbrt-v4's 1.5)."""

import math
from dataclasses import dataclass

from pathtrace.device.features import GENERIC, choice_glue

FILTERS = ("box", "tent", "gaussian")
DEFAULT_RADIUS = {"box": 0.5, "tent": 1.0, "gaussian": None}    # gaussian: 4 stddev
MAX_RADIUS = 32.0       # pixels: wider is no longer a pixel filter
MIN_WIDTH = 1e-3        # pixels: the narrowest radius or stddev (float32 squares of less underflow)


@dataclass(frozen=True)
class PixelFilter:
    name: str = "box"
    radius: float = None       # pixels; None: the type's default (set on construction)
    stddev: float = 0.5        # gaussian: pixels

    def __post_init__(self):
        if self.radius is None and self.name in FILTERS:
            default = 4 * self.stddev if self.name == "gaussian" else DEFAULT_RADIUS[self.name]
            object.__setattr__(self, "radius", default)

    def check(self) -> "PixelFilter":
        """Raises ValueError("<field>: <problem>") for the first field out of range."""
        if self.name not in FILTERS:
            raise ValueError(f"type: must be box, tent or gaussian, got {self.name!r}")
        if self.name == "gaussian" and not MIN_WIDTH <= self.stddev <= MAX_RADIUS:
            raise ValueError(f"stddev: must be in [{MIN_WIDTH:g}, {MAX_RADIUS:g}] pixels, got {self.stddev:g}")
        if not MIN_WIDTH <= self.radius <= MAX_RADIUS:
            raise ValueError(f"radius: must be in [{MIN_WIDTH:g}, {MAX_RADIUS:g}] pixels, got {self.radius:g}")
        return self

    def params(self) -> tuple:
        """RenderParams.filter (kernels/filters/<name>.cl)."""
        r = self.radius
        if self.name == "gaussian":
            return (r, self.stddev, math.exp(-r * r / (2 * self.stddev ** 2)), 0.0)
        return (r, 0.0, 0.0, 0.0)


def kernel_parts(name: str) -> list:
    """(name, source) of a program's filter: its file (GENERIC: every one of FILTERS) and the
    sample_filter that calls it."""
    names = FILTERS if name == GENERIC else (name,)
    glue = choice_glue("float2 sample_filter(const RenderParams *p, float2 u, Rng *rng)",
                       "sample_{}_filter(p, u, rng)", FILTERS, name, "filter_type")
    # the density of its offsets along an axis, which bidirectional path tracing splats by
    glue += "#ifdef BDPT\n" + choice_glue("float pdf_filter(const RenderParams *p, float x)",
                                          "pdf_{}_filter(p, x)", FILTERS, name, "filter_type") + "#endif\n"
    return [*((f"filters/{n}.cl", None) for n in names), ("app/filters.py: kernel_parts", glue)]
