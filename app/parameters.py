"""A type's parameters, declared once, beside the type: each parameter's name in pathtrace's TOML
format, in Mitsuba 3 and in pbrt-v4 (any but the first may be absent), its kind, its default, its
conversion from each format, and its one-line documentation. The three scene readers read a type's
parameters through these declarations (each reading a kind in its own syntax), and the parameter
tables of docs/scene-format.md, docs/mitsuba.md and docs/pbrt.md are generated from them
(parameter_table; app/scene/format_tables.py writes them, tests/test_parameters.py keeps them in
step).

This module imports nothing of pathtrace's (it knows a texture by its bounds_as), so that any
type's host module may import it (the material, texture, light and camera modules are imported by
pathtrace.scene, not the reverse)."""

from dataclasses import dataclass
from typing import Callable

import numpy as np

# What a parameter holds, which decides how each reader reads it:
#   number, integer, bool, string;
#   name     a string among `choices` (an enumeration);
#   color    rgb: a number (grey) or three, or a spectrum (pbrt-v4's and Mitsuba 3's spectra,
#            converted as `spectrum` says); a texture too where `texture` is set;
#   point    a position, transformed by the element's frame (Mitsuba's to_world, pbrt's CTM);
#   vector   a direction, transformed likewise;
#   image    an image file, named relative to the scene file, which the reader reads
#            (app/textures/bitmap.py: read_image) into an Image, raw (8-bit values as linear,
#            not sRGB) where the element's `raw` is true;
#   texture  a texture, never a constant (a normal map);
#   points, normals, pairs, integers, numbers
#            arrays (a mesh's vertices, normals, texture coordinates and indices; a camera's
#            screen window), as a format writes them out: pbrt-v4's point3, normal, point2,
#            integer and float arrays, flat, of any length (the type checks it).
KINDS = ("number", "integer", "bool", "string", "name", "color", "point", "vector", "image", "texture", "points",
         "normals", "pairs", "integers", "numbers")
FORMATS = ("toml", "mitsuba", "pbrt")
# how a spectrum becomes rgb (app/scene/spectra.py): a reflectance (bounded by 1), an illuminant
# (luminance 1, as pbrt-v4 normalises a light's spectrum) or unbounded (an IOR: its mean)
SPECTRA = ("reflectance", "illuminant", "unbounded")


class _Same:
    """The format's default is pathtrace's (the type's own default applies)."""

    def __repr__(self):
        return "SAME"


SAME = _Same()
FRAME = "frame"     # a point's or vector's default in a format: the element's frame's origin or +z


@dataclass(frozen=True)
class Parameter:
    name: str                    # pathtrace's name, in TOML files and the Python API
    kind: str                    # one of KINDS
    default: object = None       # pathtrace's default; None: required, unless `optional`
    low: float = None            # the range of a number or colour (a texture's bounds): None, open
    high: float = None
    doc: str = ""                # one line, for the generated tables
    choices: tuple = ()          # a name's values
    texture: bool = False        # a colour or number that a texture may give
    spectrum: str = "reflectance"    # how a colour given as a spectrum is read (SPECTRA)
    mitsuba: str = None          # Mitsuba 3's name; None: Mitsuba's plugin has no such parameter
    pbrt: str = None             # pbrt-v4's name; None: likewise
    mitsuba_default: object = SAME   # the format's default where it differs from pathtrace's
    pbrt_default: object = SAME      # (FRAME: a point's or vector's, the element's frame)
    from_mitsuba: Callable = None    # (value as the file gives it, {format name: value} of the
    from_pbrt: Callable = None       # element) -> pathtrace's value; None: the value as it is
    optional: bool = False       # without a default, and not required (the type makes do)
    pbrt_kind: str = None        # the kind pbrt-v4 gives it as, where not `kind` (from_pbrt converts it)
    raw: bool = False            # an image of data, read raw whatever the element says (a normal map)

    def __post_init__(self):
        assert self.kind in KINDS and self.pbrt_kind in (None, *KINDS) and self.spectrum in SPECTRA, self

    def named(self, fmt: str) -> str | None:
        """Its name in the format fmt (FORMATS), None where that format has none."""
        return self.name if fmt == "toml" else getattr(self, fmt)

    def default_in(self, fmt: str):
        """Its default in fmt: SAME, FRAME, or a value of pathtrace's."""
        return SAME if fmt == "toml" else getattr(self, f"{fmt}_default")

    def convert(self, fmt: str, value, given: dict):
        """pathtrace's value of what a file of format fmt gives, `given` holding the element's
        values by the format's names (a conversion may need another)."""
        convert = None if fmt == "toml" else getattr(self, f"from_{fmt}")
        return value if convert is None else convert(value, given)


def read(parameters, fmt: str, get: Callable, given: dict = None) -> dict:
    """The values of `parameters` that an element of a file in format fmt gives, by pathtrace's
    names, converted: get(parameter, the format's name) is the value the element gives (read by the
    parameter's kind, in the format's syntax), or None. A parameter absent from the element takes
    its format default where that differs from pathtrace's (in the format's terms, converted as a
    given value is; FRAME is left to the reader); the others are left out, for the type's own
    defaults to fill in. Format-only parameters (name None) are read for the conversions alone.
    `given`, where passed, is filled with the element's values by the format's names (defaults
    included), for a type's own mapping of the format's element (a pbrt-v4 texture's from_pbrt)."""
    given = {} if given is None else given
    for p in parameters:
        name = p.named(fmt)
        if name is not None:
            value = get(p, name)
            given[name] = p.default_in(fmt) if value is None else value
            if p.name is None and given[name] is SAME:
                given[name] = None          # a format-only parameter absent, of no default
    values = {}
    for p in parameters:
        name = p.named(fmt)
        value = given.get(name) if name is not None else p.default_in(fmt)
        if p.name is None or value is None or value is SAME:
            continue
        values[p.name] = value if value is FRAME else p.convert(fmt, value, given)
    return values


def missing(parameters, values: dict) -> list:
    """The required `parameters` (no default, not optional) that `values` lacks."""
    return [p for p in parameters if p.name and p.default is None and not p.optional and p.name not in values]


def out_of_range(parameters, values: dict) -> ValueError | None:
    """The first of `values` outside its parameter's range [low, high] (a number or colour not
    finite too), as a type's ValueError ("<name>: <problem>"), or None: the one range check of
    the readers' values (the TOML reader's numbers are checked as its syntax reads them, its
    textures here). A parameter of neither bound is not checked (the readers refuse NaN and inf
    as they parse them). A texture is checked by its bounds (Texture.bounds_as: a number's by
    their luminance, as the kernels read it); an integer as Python compares it (a file's integer
    may be of any size)."""
    for p in parameters:
        value = values.get(p.name)
        if p.kind not in ("integer", "number", "color") or value is None or isinstance(value, str) or \
                (p.low is None and p.high is None):
            continue
        if p.kind == "integer":
            if (p.low is None or value >= p.low) and (p.high is None or value <= p.high):
                continue
            return ValueError(f"{p.name}: must be in {p.low}..{p.high}, got {value}")
        low, high = value.bounds_as(p.kind) if hasattr(value, "bounds_as") else (np.min(value), np.max(value))
        # compared as the kernels hold them, in float32: a value read back from a material's row
        # (1e-06 is 9.9999997e-07 there) is within the bound it was checked against
        # (a Python integer beyond any float, which the API may be given, as infinity)
        low, high = (v if not isinstance(v, int) or abs(v) < 1e300 else (1 if v > 0 else -1) * np.inf for v in (low, high))
        with np.errstate(over="ignore"):
            low32, high32 = np.float32(low), np.float32(high)
        if np.isfinite(low32) and np.isfinite(high32) and (p.low is None or low32 >= np.float32(p.low)) and \
                (p.high is None or high32 <= np.float32(p.high)):
            continue
        bound = f"[{p.low:g}, " if p.low is not None else "(-inf, "
        bound += f"{p.high:g}]" if p.high is not None else "inf)"
        return ValueError(f"{p.name}: must lie in {bound}, got " + (f"{low:.4g}" if not low < high else
                                                                   f"from {low:.4g} to {high:.4g}"))
    return None


def format_names(parameters, fmt: str) -> dict:
    """{pathtrace's name: the format fmt's} of `parameters` that fmt has, by which a reader's
    message names the parameter that a type's ValueError ("<name>: <problem>") names."""
    return {p.name: p.named(fmt) for p in parameters if p.name and p.named(fmt)}


def by_format(types, fmt: str) -> dict:
    """{a type's name in the format fmt: the type} of the types (with a `formats` attribute: {format:
    name or tuple of names}) that fmt has."""
    out = {}
    for t in types:
        names = getattr(t, "formats", {}).get(fmt, ())
        for name in (names,) if isinstance(names, str) else names:
            out[name] = t
    return out


def _shown(value) -> str:
    if value is None:
        return "required"
    if value is SAME:
        return "="
    if isinstance(value, float) and value == int(value) and abs(value) < 1e6:
        return f"{value:g}"
    if isinstance(value, (list, tuple)):
        return " ".join(_shown(v) for v in value)
    return str(value) if not isinstance(value, bool) else str(value).lower()


def parameter_table(parameters, formats=FORMATS) -> str:
    """A Markdown table of `parameters`: pathtrace's name, kind and default, each format's name
    (and default, where it differs), and the documentation. Generated into the docs."""
    heads = {"toml": "TOML", "mitsuba": "Mitsuba 3", "pbrt": "pbrt-v4"}
    lines = ["| " + " | ".join([heads[f] for f in formats] + ["kind", "default", "meaning"]) + " |",
             "|" + "---|" * (len(formats) + 3)]
    for p in parameters:
        cells = []
        for f in formats:
            name = p.named(f)
            default = p.default_in(f)
            cell = f"`{name}`" if name else "—" if default is SAME else ""
            if default is not SAME:
                cell += (" " if cell else "") + ("(its frame)" if default == FRAME else f"(default {_shown(default)})")
            if f != "toml" and getattr(p, f"from_{f}") is not None:
                cell += " †"
            cells.append(cell)
        kind = p.kind + (" or texture" if p.texture else "")
        if p.choices:
            kind += ": " + ", ".join(p.choices)
        default = "—" if p.name is None else "" if p.optional else _shown(p.default)
        cells += [kind, default, p.doc.replace("|", "\\|")]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
