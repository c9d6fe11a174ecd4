"""Pixel filters: where in and around its pixel each sample lands, by filter importance sampling
(kernels/camera.cl). Each type is a kernel file kernels/filters/<name>.cl, with Mitsuba 3's and
pbrt-v4's parameters: box (radius 0.5), tent (pbrt-v4's triangle; radius 1, pbrt-v4's 2) and
gaussian (stddev 0.5; radius 4 stddev, pbrt-v4's 1.5)."""

import math
from dataclasses import dataclass

from pathtrace.device.features import GENERIC, choice_glue
from pathtrace.errors import cut

FILTERS = ("box", "tent", "gaussian")
DEFAULT_RADIUS = {"box": 0.5, "tent": 1.0, "gaussian": None}    # gaussian: 4 stddev
PBRT_RADIUS = {"box": 0.5, "triangle": 2.0, "gaussian": 1.5, "mitchell": 2.0, "lanczos": 4.0}   # pbrt-v4's defaults
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
            raise ValueError(f"type: must be {', '.join(FILTERS[:-1])} or {FILTERS[-1]}, got {self.name!r}")
        if self.name == "gaussian" and not MIN_WIDTH <= self.stddev <= MAX_RADIUS:
            raise ValueError(f"stddev: must be in [{MIN_WIDTH:g}, {MAX_RADIUS:g}] pixels, got {self.stddev:g}")
        if not MIN_WIDTH <= self.radius <= MAX_RADIUS:
            raise ValueError(f"radius: must be in [{MIN_WIDTH:g}, {MAX_RADIUS:g}] pixels, got {self.radius:g}")
        return self

    @classmethod
    def from_mitsuba(cls, kind: str, get, warn) -> "PixelFilter":
        """Mitsuba 3's rfilter `kind` (get(name, default): a float property): its box (radius
        0.5), tent (radius, 1) and gaussian (stddev 0.5, radius 4 stddev); the filters of
        negative lobes become its gaussian, with a warning. Raises ValueError as check()."""
        if kind not in FILTERS:
            warn(f"pathtrace has no {kind} filter (its weights go negative, which filter importance sampling "
                 "cannot follow); it uses Mitsuba's gaussian")
            return cls("gaussian")
        return cls(kind, get("radius", None) if kind == "tent" else None,
                   get("stddev", 0.5) if kind == "gaussian" else 0.5).check()

    @classmethod
    def from_pbrt(cls, kind: str, get, warn) -> "PixelFilter":
        """pbrt-v4's PixelFilter `kind` (get(name, default): a float parameter): box, triangle and
        gaussian of their xradius and yradius (one radius, their mean, with a warning where they
        differ) and the gaussian's sigma (src/pbrt/filters.cpp, the filters' Create); mitchell and
        lanczos, of negative lobes, become its gaussian, with a warning. Raises ValueError
        ("<pbrt name>: <problem>")."""
        if kind not in PBRT_RADIUS:
            raise ValueError(f"type: unknown pixel filter '{cut(kind)}' (pbrt-v4 has {', '.join(PBRT_RADIUS)})")
        rx, ry = get("xradius", PBRT_RADIUS[kind]), get("yradius", PBRT_RADIUS[kind])
        if rx != ry:
            warn(f"pathtrace's filters have one radius; it uses {(rx + ry) / 2:g}")
        if kind in ("mitchell", "lanczos"):
            warn(f"pathtrace has no {kind} filter (its weights go negative); it uses pbrt's gaussian")
            return cls("gaussian", 1.5, 0.5)
        name = {"triangle": "tent"}.get(kind, kind)
        try:
            return cls(name, (rx + ry) / 2, get("sigma", 0.5) if kind == "gaussian" else 0.5).check()
        except ValueError as e:
            field, problem = str(e).split(": ", 1)
            raise ValueError(f"{ {'radius': 'xradius', 'stddev': 'sigma'}[field]}: {problem}") from None

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
