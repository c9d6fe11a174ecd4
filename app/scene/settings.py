"""The render settings a scene file gives (RenderSettings), declared once (app/parameters.py) as
the formats' elements hold them: the film's size (Mitsuba 3's <film>, pbrt-v4's Film), the
samples per pixel (<sampler>, Sampler) and the integrator's depth and light sampler
(<integrator>, Integrator), each with its names, defaults and conversions in the formats; TOML's
[render] table holds them all, with settings of pathtrace's own. Which integrator a format's
type becomes is each reader's (it warns of the ones pathtrace replaces)."""

from dataclasses import replace

from pathtrace.parameters import Parameter, read
from pathtrace.rendering.choices import INTEGRATORS, LIGHT_SAMPLERS
from pathtrace.scene.description import RenderSettings
from pathtrace.scene.meshes import MAX_COORDINATE
from pathtrace.scene.validate import SETTING_RANGES

# pbrt-v4's light samplers (LightSampler::Create) as pathtrace's: each unbiased, so a choice by
# power or by pathtrace's light tree draws the same image in expectation, with more or less noise
PBRT_LIGHT_SAMPLERS = {"bvh": "auto", "exhaustive": "auto", "power": "power", "uniform": "power"}


def _integer(name: str, **formats) -> Parameter:
    """An integer setting of RenderSettings, its default and range (validate.SETTING_RANGES) the
    settings'."""
    low, high = SETTING_RANGES[name]
    return Parameter(name, "integer", getattr(RenderSettings, name), low=low, high=high, **formats)


def _mitsuba_depth(depth, given):
    """Mitsuba 3's max_depth: -1 unlimited (pathtrace's 0), 0 nothing at all."""
    if not -1 <= depth < 2**31:
        raise ValueError(f"max_depth: must be -1 (unlimited) to {2**31 - 1}, got {depth}")
    if depth == 0:
        raise ValueError("max_depth: 0 renders nothing; pathtrace needs 1 or more (or -1)")
    return 0 if depth == -1 else depth


def _pbrt_depth(depth, given):
    """pbrt-v4's maxdepth counts bounces: its N is pathtrace's (Mitsuba's) N + 1 vertices."""
    if not 0 <= depth < 2**31 - 1:
        raise ValueError(f"maxdepth: must be in 0..{2**31 - 2}, got {depth}")
    return depth + 1


def _pbrt_light_sampler(name, given):
    if name not in PBRT_LIGHT_SAMPLERS:
        raise ValueError(f"lightsampler: must be {', '.join(sorted(PBRT_LIGHT_SAMPLERS))}, got {name!r}")
    return PBRT_LIGHT_SAMPLERS[name]


class Element:
    """One element of a format's settings: its parameters, and what the formats' element has and
    pathtrace has not ({format: {name: why}}, as a light's: warned of where given; why None:
    read, not warned of)."""
    parameters: tuple = ()
    unsupported: dict = {}


class Film(Element):
    parameters = (_integer("width", doc="the image's width in pixels", mitsuba="width", mitsuba_default=768,
                           pbrt="xresolution", pbrt_default=1280),
                  _integer("height", doc="its height", mitsuba="height", mitsuba_default=576, pbrt="yresolution",
                           pbrt_default=720))
    # the output's format and name are its file name's (render -o), whatever these say
    unsupported = {"mitsuba": dict.fromkeys(("file_format", "component_format")), "pbrt": {"string filename": None}}


def _pbrt_stratified(x, given):
    """pbrt-v4's stratified sampler's samples per pixel: xsamples times ysamples."""
    y, most = given["ysamples"], SETTING_RANGES["spp"][1]
    for name, n in (("xsamples", x), ("ysamples", y)):
        if not 1 <= n <= most:
            raise ValueError(f"{name}: must be in 1..{most}, got {n}")
    if x * y > most:
        raise ValueError(f"xsamples: times ysamples must be at most {most} (samples per pixel), got {x * y}")
    return x * y


class Sampler(Element):
    parameters = (_integer("spp", doc="samples per pixel", mitsuba="sample_count", mitsuba_default=4,
                           pbrt="pixelsamples", pbrt_default=16),)


class StratifiedSampler(Element):
    """pbrt-v4's stratified sampler, which takes its samples per pixel (src/pbrt/samplers.cpp,
    StratifiedSampler::Create) as xsamples times ysamples; its jitter is its own, warned of as
    any name not read."""
    parameters = (replace(Sampler.parameters[0], pbrt="xsamples", pbrt_default=4, from_pbrt=_pbrt_stratified),
                  Parameter(None, "integer", pbrt="ysamples", pbrt_default=4, doc="its samples per pixel along y"))


# each format's samplers that take their samples per pixel otherwise than Sampler does
SAMPLERS = {"pbrt": {"stratified": StratifiedSampler}}


class Integrator(Element):
    # each format's integrators that pathtrace has (README, Integrators) or renders with its
    # nearest, {type: (pathtrace's, a note of the approximation or None)}; its others are
    # rendered with the path tracer, with a warning
    types = {"mitsuba": {**dict.fromkeys(("path", "volpath", "prb", "prbvolpath"), ("path", None)),
                         "bdpt": ("bdpt", None), "ptracer": ("ptracer", None)},     # Mitsuba 0.6's bdpt
             "pbrt": {"path": ("path", None), "volpath": ("path", None), "bdpt": ("bdpt", None),
                      "mlt": ("bdpt", "pathtrace renders mlt with bdpt, the nearest method it has"),
                      "sppm": ("bdpt", None),      # its photons' radius a note of its own (pbrt/options.py)
                      # light tracing; pathtrace's (ptracer) leaves out an environment, which bdpt renders
                      "lightpath": ("bdpt", "pathtrace renders lightpath with bdpt, whose light subpaths joined to "
                                            "the camera are light tracing's")}}
    parameters = (
        _integer("max_depth", doc="the longest path in vertices (1: emitters seen directly), 0 unlimited; "
                 "Mitsuba's -1 is unlimited, pbrt-v4's counts bounces (N + 1 vertices)", mitsuba="max_depth",
                 mitsuba_default=-1, from_mitsuba=_mitsuba_depth, pbrt="maxdepth", pbrt_default=5,
                 from_pbrt=_pbrt_depth),
        Parameter("light_sampler", "name", RenderSettings.light_sampler, choices=LIGHT_SAMPLERS,
                  doc="how next-event estimation chooses a light; pbrt-v4's bvh is auto, its uniform power",
                  pbrt="lightsampler", pbrt_default="bvh", from_pbrt=_pbrt_light_sampler))


# the [render] table's: the elements' and pathtrace's own (its filter and Russian roulette are
# read by the TOML reader: a name or a table, a name or true and false)
RENDER = Film.parameters + Sampler.parameters + Integrator.parameters + (
    _integer("seed", doc="the first sample's seed"),
    Parameter("nee", "bool", RenderSettings.nee, doc="next-event estimation with MIS"),
    Parameter("integrator", "name", RenderSettings.integrator, choices=INTEGRATORS, doc="the estimator"),
    Parameter("photon_radius", "number", RenderSettings.photon_radius, low=0.0, high=MAX_COORDINATE,
              doc="with bdpt: caustic photons gathered within it at first; 0: none"))


def defaults(fmt: str) -> RenderSettings:
    """The settings of a file of format fmt that gives none: the defaults of its elements."""
    elements = Film.parameters + Sampler.parameters + Integrator.parameters
    return RenderSettings(**read(elements, fmt, lambda p, name: None))
