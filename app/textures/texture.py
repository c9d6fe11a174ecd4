"""Textures as scene files state them, and the interface every texture type implements on the
host: its inputs, how it packs into a TEXTURE row that its kernel file kernels/textures/<name>.cl
reads (documented at that file's top), and its mean and maximum, which stand for it where the
host needs one number (a BSDF's lobe choice, an emitter's power, a range check)."""

import sys
from dataclasses import dataclass, field

import numpy as np

from pathtrace.parameters import Parameter

IDENTITY_UV = np.eye(3)
# pbrt-v4's uv mapping, which every texture of a pbrt_uv reads (src/pbrt/textures.cpp,
# TextureMapping2D::Create: UVMapping su u + du, sv v + dv); TextureType.pbrt_to_uv maps it
PBRT_MAPPING = (Parameter(None, "string", pbrt="mapping", pbrt_default="uv"),
                Parameter(None, "number", pbrt="uscale", pbrt_default=1.0),
                Parameter(None, "number", pbrt="vscale", pbrt_default=1.0),
                Parameter(None, "number", pbrt="udelta", pbrt_default=0.0),
                Parameter(None, "number", pbrt="vdelta", pbrt_default=0.0))

# name -> TextureType, filled by app/textures/registry.py: the types' modules import this one, so
# it cannot import them (or the registry) itself
KINDS = {}


@dataclass(eq=False)
class Texture:
    """One texture: a type of the registry (pathtrace.textures.TEXTURES) and its parameters.
    An input (a checkerboard's colours, a scale's factor) is a number, three numbers, or a
    Texture; `to_uv` (a 3x3 matrix acting on (u, v, 1)) transforms the surface's uv first."""
    type: str
    params: dict = field(default_factory=dict)
    name: str | None = None

    def __repr__(self) -> str:
        """One line: its type, name and inputs (an image by its size and file, never its texels)."""
        def value(v):
            if isinstance(v, Texture):
                return repr(v)
            if hasattr(v, "texels"):
                h, w = v.texels.shape[:2]
                return f"{getattr(v, 'path', None) or 'image'} ({w}x{h})"
            a = np.asarray(v)
            return f"{a.tolist()}" if a.size <= 4 else f"array {a.shape}"
        inputs = ", ".join(f"{k}={value(v)}" for k, v in self.params.items() if k != "to_uv")
        return f"<Texture {self.type}{f' {self.name!r}' if self.name else ''}: {inputs}>"

    @property
    def kind(self):
        return KINDS[self.type]

    def mean(self) -> np.ndarray:
        """The texture's mean colour over the unit square of uv (an estimate for those that
        combine textures), rgb."""
        return deep(lambda: self.kind.mean(self))

    def maximum(self) -> np.ndarray:
        """An upper bound of its values, rgb."""
        return deep(lambda: self.kind.bounds(self))[1]

    def minimum(self) -> np.ndarray:
        """A lower bound of its values, rgb."""
        return deep(lambda: self.kind.bounds(self))[0]

    def bounds_as(self, kind: str) -> tuple:
        """(lowest, highest) of its values as a parameter of `kind` reads them: a colour's
        channels, a number's luminance (kernels/texture.cl)."""
        low, high = deep(lambda: self.kind.bounds(self))
        return (np.min(low), np.max(high)) if kind == "color" else (float(low @ LUMINANCE), float(high @ LUMINANCE))

    def inputs(self) -> list:
        """Its inputs that are textures."""
        return [self.params[n] for n in self.kind.inputs if isinstance(self.params.get(n), Texture)]


LUMINANCE = np.array([0.212671, 0.715160, 0.072169])     # kernels/texture.cl: luminance
# the recursion limit while a texture tree's mean or bounds are computed, a few calls per level:
# pbrt-v4 files chain textures thousands deep. Python >= 3.11 (pyproject.toml) makes pure-Python
# calls without growing the C stack, so the limit only bounds memory
DEEP_RECURSION = 100_000


def deep(call):
    """call(), with the recursion limit raised to DEEP_RECURSION for a deep texture tree."""
    limit = sys.getrecursionlimit()
    if limit >= DEEP_RECURSION:
        return call()
    sys.setrecursionlimit(DEEP_RECURSION)
    try:
        return call()
    finally:
        sys.setrecursionlimit(limit)


def input_mean(value) -> np.ndarray:
    return value.mean() if isinstance(value, Texture) else np.broadcast_to(np.asarray(value, np.float64), 3)


def input_bounds(value) -> tuple:
    if isinstance(value, Texture):
        return value.kind.bounds(value)
    v = np.broadcast_to(np.asarray(value, np.float64), 3)
    return v, v


def uv_matrix(to_uv) -> np.ndarray:
    """A uv transform as the 3x3 matrix acting on (u, v, 1): given as 3x3, or as the 4x4 of a
    scene file's transform, whose x, y and translation parts act on uv (Mitsuba 3's to_uv)."""
    m = np.asarray(to_uv, np.float64)
    if m.shape == (4, 4):
        m = m[np.ix_([0, 1, 3], [0, 1, 3])]
    if m.shape != (3, 3) or not np.all(np.isfinite(m)):
        raise ValueError("to_uv must be a finite 3x3 or 4x4 matrix")
    return m


class TextureType:
    """One texture type. Subclasses set name, doc, parameters (app/parameters.py: their names in
    the formats, defaults, docs; those that a texture may give, `texture` set, are its inputs 0 to
    2, in order) and define pack (the type's own fields) and mean."""
    name: str
    doc: str = ""
    parameters: tuple = ()
    formats: dict = {}        # its names in other formats: {"mitsuba": name, "pbrt": name}
    format_only: tuple = ()   # Parameters a format's texture has and this type keeps none of (name
                              # None), read for the conversions and from_pbrt
    pbrt_floats: tuple = ()   # its inputs that pbrt-v4 reads as float textures whatever the texture's
    pbrt_uv: float = 0.0      # the scale of pbrt-v4's (s, t), mapped by uscale, vscale, udelta and
                              # vdelta, in its uv; 0: pbrt-v4's texture reads no mapping
    inputs: tuple = ()        # set from parameters
    defaults: dict = {}       # likewise

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.inputs = tuple(p.name for p in cls.parameters if p.texture)
        cls.defaults = {p.name: p.default for p in cls.parameters if p.default is not None}
    # parameter sets that the conformance suite (tests/test_texture_conformance.py) evaluates in
    # the kernel against mean and bounds; an input may be a Texture of other parameters, which
    # the suite completes. Each type declares its own, one at least, where its mean is exact
    # (a combining type's mean is an estimate where two of its inputs vary together)
    examples: tuple = ()

    @property
    def leaf(self) -> bool:
        """Whether it reads no other texture, and so may be another's input."""
        return not self.inputs

    def complete(self, params: dict) -> dict:
        """The parameters with defaults filled in and checked; raises ValueError."""
        values = {**self.defaults, **params}
        values["to_uv"] = uv_matrix(values.get("to_uv", IDENTITY_UV))
        for name in self.inputs:
            value = values[name]
            if not isinstance(value, Texture):
                v = np.asarray(value, np.float64)
                if v.size not in (1, 3) or not np.all(np.isfinite(v)):
                    raise ValueError(f"{name} must be a number, three numbers or a texture")
                values[name] = np.broadcast_to(v.reshape(-1), 3).copy()
        return values

    def from_pbrt(self, values: dict, given: dict, warn):
        """What a pbrt-v4 Texture of this type is: a Texture (or a constant), from its declared
        parameters' values by pathtrace's names (converted; to_uv its mapping) and by pbrt-v4's
        (`given`); warn(text) tells what pathtrace approximates. Raises ValueError."""
        return Texture(self.name, self.complete(values))

    def pbrt_to_uv(self, given: dict, warn) -> np.ndarray:
        """pbrt-v4's uv mapping (PBRT_MAPPING's values in `given`) as pathtrace's to_uv, on the
        flipped v that the pbrt reader gives meshes: t = 1 - (sv v_pbrt + dv) with v_pbrt = 1 - v;
        times pbrt_uv."""
        if given["mapping"] != "uv":
            warn(f"pathtrace maps textures by uv only; the {given['mapping']} mapping is taken as uv")
        su, sv, du, dv = given["uscale"], given["vscale"], given["udelta"], given["vdelta"]
        m = np.array([[su, 0, du], [0, sv, 1 - sv - dv], [0, 0, 1.0]])
        m[:2] *= self.pbrt_uv
        return m

    def pack(self, texture: Texture, row, texels):
        """Fills the type's own fields of `row` (a TEXTURE record), storing any image in
        `texels` (a TexelStore)."""

    def mean(self, texture: Texture) -> np.ndarray:
        raise NotImplementedError

    def bounds(self, texture: Texture) -> tuple:
        """(lowest, highest) of its values, rgb, or bounds of them."""
        raise NotImplementedError
