"""Pixel filters: where in and around its pixel each sample lands, by filter importance sampling
(kernels/camera.cl). Each type is a kernel file kernels/filters/<name>.cl, declared here with its
parameters in the three formats (app/parameters.py): box (radius 0.5), tent (pbrt-v4's
triangle; radius 1, pbrt-v4's 2) and gaussian (stddev 0.5; radius 4 stddev, pbrt-v4's 1.5)."""

import math
from dataclasses import dataclass

from pathtrace.device.features import GENERIC, choice_glue
from pathtrace.errors import cut
from pathtrace.parameters import Parameter, by_format, read
from pathtrace.rendering.choices import FILTERS

MAX_RADIUS = 32.0       # pixels: wider is no longer a pixel filter
MIN_WIDTH = 1e-3        # pixels: the narrowest radius or stddev (float32 squares of less underflow)


def _radius(default, pbrt_default, doc, **mitsuba) -> tuple:
    """A type's radius, and pbrt-v4's xradius and yradius, of which pathtrace's one radius is the
    mean (FilterType.make warns where they differ)."""
    return (Parameter("radius", "number", default, optional=default is None, doc=doc, pbrt="xradius",
                      pbrt_default=pbrt_default, from_pbrt=lambda x, given: (x + given["yradius"]) / 2, **mitsuba),
            Parameter(None, "number", pbrt="yradius", pbrt_default=pbrt_default,
                      doc="pathtrace's filters have one radius: the mean of xradius and yradius"))


@dataclass(frozen=True)
class FilterType:
    """A filter type: its names in Mitsuba 3 and pbrt-v4 and its parameters (app/parameters.py),
    which the readers read it by."""
    name: str
    formats: dict
    parameters: tuple
    doc: str
    unsupported = {}

    def make(self, values: dict, given: dict = None, warn=None) -> "PixelFilter":
        """The filter of a file's values (app/parameters.py: read; `given`, by the format's
        names), checked: raises ValueError("<field>: <problem>")."""
        given = given or {}
        if given.get("xradius") != given.get("yradius"):
            warn(f"pathtrace's filters have one radius; it uses {values['radius']:g}")
        try:
            return PixelFilter(self.name, **values).check()
        except ValueError as e:
            field, _, problem = str(e).partition(": ")
            if field == "radius" and "xradius" in given:
                raise ValueError(f"'xradius' and 'yradius': {problem} (their mean)") from None
            raise


TYPES = {t.name: t for t in (     # in FILTERS' order (rendering/choices.py: the command line's)
    FilterType("box", {"mitsuba": "box", "pbrt": "box"}, _radius(0.5, 0.5, "pixels (Mitsuba 3's box has 0.5)"),
               "weight 1 within the radius: the pixel itself at 0.5"),
    FilterType("tent", {"mitsuba": "tent", "pbrt": "triangle"}, _radius(1.0, 2.0, "pixels", mitsuba="radius"),
               "weights 1 - |x| / radius per axis"),
    FilterType("gaussian", {"mitsuba": "gaussian", "pbrt": "gaussian"},
               (Parameter("stddev", "number", 0.5, doc="pixels", mitsuba="stddev", pbrt="sigma"),
                *_radius(None, 1.5, "pixels; by default 4 stddev (Mitsuba 3's always)")),
               "weights exp(-x^2 / (2 stddev^2)) less their value at the radius, per axis"))}
# the formats' filters whose weights go negative, which filter importance sampling cannot follow:
# pathtrace's gaussian of the format's defaults stands in, with a warning (Mitsuba 3: any it has not)
NEGATIVE_LOBES = {"pbrt": ("mitchell", "lanczos")}


def format_type(fmt: str, kind: str, warn) -> FilterType:
    """The type of a filter of format fmt ("mitsuba", "pbrt") and type `kind`; where pathtrace has
    none, None, with a warning of the gaussian that stands in. Raises ValueError for a type
    pbrt-v4 has not."""
    types = by_format(TYPES.values(), fmt)
    if kind in types:
        return types[kind]
    if fmt == "pbrt" and kind not in NEGATIVE_LOBES[fmt]:
        known = ", ".join([*types, *NEGATIVE_LOBES[fmt]])
        raise ValueError(f"unknown pixel filter '{cut(kind)}' (pbrt-v4 has {known})")
    warn(f"pathtrace has no {kind} filter (its weights go negative, which filter importance sampling cannot "
         f"follow); it uses {'pbrt' if fmt == 'pbrt' else 'Mitsuba'}'s gaussian")
    return None


def format_default(fmt: str) -> "PixelFilter":
    """The filter of a file of format fmt that gives none, and the one that stands in for a
    filter of negative lobes: its gaussian, of its defaults."""
    return TYPES["gaussian"].make(read(TYPES["gaussian"].parameters, fmt, lambda p, name: None))


@dataclass(frozen=True)
class PixelFilter:
    name: str = "box"
    radius: float = None       # pixels; None: the type's default (set on construction)
    stddev: float = 0.5        # gaussian: pixels

    def __post_init__(self):
        if self.radius is None and self.name in FILTERS:
            default = 4 * self.stddev if self.name == "gaussian" else TYPES[self.name].parameters[0].default
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
