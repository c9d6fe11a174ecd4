"""The interface every material type implements on the host: its parameters (Mitsuba 3's names
where Mitsuba has the material), their checks, and how they pack into the MATERIAL struct that
its kernel file kernels/bsdfs/<name>.cl reads, through accessors generated from the slots its
parameters and derived values declare (Param.slot, BSDFType.derived; app/device/slots.py)."""

from dataclasses import dataclass, replace

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.device.slots import read_slot, write_slot
from pathtrace.textures.texture import KINDS, LUMINANCE, Texture, deep

# MATERIAL.flags bits, as kernels/types.h defines them
TWOSIDED = 1        # the same BSDF on both sides
DELTA = 2           # every lobe is a delta: no light sampling there
TRANSMISSIVE = 4    # an interface seen from both sides
MASKED = 8          # it has an opacity (an alpha mask), the BSDF telling them apart
NULL = 16           # no surface, only a boundary between media (kernels/volume.cl)
EMITS_BACK = 32     # its emission leaves its back as well as its front (pbrt's twosided area light)
PBRT_PERTURBATION = 64     # its normal or bump map perturbs as pbrt-v4's do (Material.perturbation)


@dataclass(frozen=True)
class Param(Parameter):
    """A material's parameter (app/parameters.py): its kind "color" (a number or three),
    "number", "bool", or "name" (a string of `names`, which resolve() turns into other
    parameters); its range [low, high] (high None: unbounded); its names in the formats."""
    low: float = 0.0
    names: dict = None        # for "number": named values accepted too; for "name": the choices
    slot: str = None          # where the kernels read it (app/device/slots.py), through the accessor
                              # <TYPE>_<NAME>(m) generated from it (registry.py: tag_source): a
                              # parameter with a slot in p0..p2 may be a texture, whose value at
                              # each hit goes there (kernels/shading.cl), unless `constant`
    constant: bool = False    # read from its slot, never given by a texture (the host derives
                              # other slots from it, or its slot is in the table)
    into: str = None          # another way to give parameter `into`, which resolve() turns it
                              # into (principled's specular, its eta): never kept itself
    pbrt_from: str = None     # the pbrt-v4 parameter a type's from_pbrt computes it from, where it
                              # has no pbrt name of its own: the pbrt reader's messages name it

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "texture", self.slot is not None and not self.constant)
        if self.kind == "name" and self.names and not self.choices:
            object.__setattr__(self, "choices", tuple(self.names))


def pbrt_clamped(value, given=None):
    """A reflectance of pbrt-v4's, which its diffuse, coated and diffuse-transmission materials
    clamp into [0, 1] where they evaluate it (src/pbrt/materials.h: DiffuseMaterial::GetBxDF's
    Clamp(texEval(reflectance, ...), 0, 1), as CoatedDiffuse's reflectance and albedo), as its
    image textures clamp an albedo's rgb after their scale (src/pbrt/textures.cpp,
    SpectrumImageTexture::Evaluate: RGBAlbedoSpectrum(Clamp(rgb, 0, 1))): a constant clamped
    here, so that a file pbrt-v4 renders renders; in a texture, each image (a bitmap, or the
    scale of one that Bitmap.from_pbrt makes) whose values may leave [0, 1] wrapped in a clamp
    texture (app/textures/clamp.py), and the whole where it still may (a scale of such images).
    A texture that stays within is as it is, and a scene of such textures compiles no clamp."""
    if not isinstance(value, Texture):
        return np.clip(np.asarray(value, np.float64), 0.0, 1.0)
    value = deep(lambda: _images_clamped(value))
    return value if _within_0_1(value) else _clamped(value)


def _within_0_1(texture: Texture) -> bool:
    return np.min(texture.minimum()) >= 0.0 and np.max(texture.maximum()) <= 1.0


def _clamped(texture: Texture) -> Texture:
    return Texture("clamp", KINDS["clamp"].complete({"tex": texture}))


def _images_clamped(texture: Texture) -> Texture:
    """The texture, its images that may leave [0, 1] clamped (a copy where any is: the file's
    named texture may stand elsewhere unclamped, as an emission)."""
    p = texture.params
    if texture.type == "bitmap" or texture.type == "scale" and isinstance(p["tex"], Texture) \
            and p["tex"].type == "bitmap" and not isinstance(p["scale"], Texture):
        return texture if _within_0_1(texture) else _clamped(texture)
    inputs = {k: _images_clamped(v) for k, v in p.items() if isinstance(v, Texture)}
    if all(v is p[k] for k, v in inputs.items()):
        return texture
    return Texture(texture.type, {**p, **inputs}, texture.name)


def constant_of(value, kind: str, summary=Texture.mean):
    """A parameter's value where the host needs a constant: a texture's mean (or another
    summary), as a colour or, for a number, its luminance (the kernel's reading of a colour
    texture as a number, kernels/texture.cl); anything else as it is."""
    if not isinstance(value, Texture):
        return value
    rgb = summary(value)
    return rgb if kind == "color" else float(np.dot(rgb, LUMINANCE))


def check_sum_at_most_one(values, a: str, b: str) -> str | None:
    """Energy conservation of two lobes: values[a] + values[b] at most 1 in each channel."""
    total = values[a] + values[b]
    if np.any(total > 1 + 1e-6):
        return (f"{a} + {b} must not exceed 1 in any channel (energy conservation), "
                f"got {[round(float(x), 6) for x in np.ravel(total)[:3]]}")
    return None


class BSDFType:
    """One material type. Subclasses set name, params and doc, and define pack/unpack over
    arrays whose leading axis is the row (so that a scene of 10^6 random spheres packs at once)."""
    name: str
    params: tuple = ()
    doc: str = ""
    formats: dict = {}        # its names in other formats: {"mitsuba": name, "pbrt": name or names}
    format_only: tuple = ()   # Parameters a format's material has and this type keeps none of
                              # (name None), read for the others' conversions (pbrt-v4's scale)
    flags: int = 0            # DELTA, TRANSMISSIVE, NULL
    kernel: bool = True       # has kernels/bsdfs/<name>.cl
    resolved_first: bool = False   # the kernels turn it into another material before any BSDF
                                   # call (a blend): its file has no eval, pdf or sample
    requires: tuple = ()      # kernel files its own builds on, compiled before it (kernels/)
    derived: tuple = ()       # the slots pack() computes (Slot), beside the parameters' own
    host_only: tuple = ()     # slotted parameters no kernel reads, kept for unpack (the editor)
    reads_as: dict = {}       # other types whose accessors the kernels apply to this type's rows
                              # (a coatedconductor's base is read as a roughconductor): {type:
                              # {their slot's name: this type's}}, slots that must coincide
    # What the conformance suite (tests/test_bsdfs.py) runs every type through:
    examples: tuple = ()      # parameter sets, as a scene file gives them; each type declares
                              # its own (a subclass does not inherit them), one at least
    reciprocal: bool = True   # f(wo, wi) = f(wi, wo) with wi on either side; refraction scales
                              # radiance by (n_i / n_t)^2 (Veach 1997, 5.2), so a refracting
                              # type is reciprocal in its reflection only
    lobe_weights: bool = False    # sample() weighs a draw by its chosen lobe alone, f_lobe cos /
                                  # (P_lobe pdf_lobe): unbiased for f cos over any region of
                                  # directions, but not eval cos / pdf draw by draw
    estimated: bool = False   # eval and pdf are stochastic estimates (pbrt-v4's LayeredBxDF):
                              # sampling is checked against them by albedo, not bin by bin

    def __init_subclass__(cls, **kwargs):
        """A type that Mitsuba 3 has takes its parameters by pathtrace's names there too (pathtrace
        follows Mitsuba's), except where a parameter names its own."""
        super().__init_subclass__(**kwargs)
        if "mitsuba" in cls.formats:
            cls.params = tuple(replace(p, mitsuba=p.mitsuba or p.name) for p in cls.params)

    def from_pbrt(self, values: dict, given: dict, warn) -> tuple | None:
        """(pathtrace's type, its values) of a pbrt-v4 material of this type's pbrt name, from its
        declared parameters' values by pathtrace's names and by pbrt-v4's (`given`; its
        format_only too), or None for no surface; warn(text) tells what pathtrace approximates.
        Raises ValueError ("<pbrt name>: <problem>")."""
        return self.name, values

    def resolve(self, values: dict) -> dict:
        """Turns names into the numbers they stand for (a named IOR; a "name" parameter, in the
        subclasses that have one); values holds the parameters a file gave. Raises ValueError
        with the problem."""
        values = dict(values)
        for p in self.params:
            value = values.get(p.name)
            if p.kind == "number" and isinstance(value, str):
                if value not in (p.names or {}):
                    raise ValueError(f"{p.name}: unknown name {value!r}"
                                     + (f" (known: {', '.join(sorted(p.names))})" if p.names else ""))
                values[p.name] = p.names[value]
        return values

    def complete(self, given: dict) -> dict:
        """The full parameter values from those a file gave: names resolved, defaults filled in,
        the combination checked. Raises ValueError with the problem."""
        values = self.resolve(given)
        for p in self.params:
            if p.kind != "name" and p.into is None and p.name not in values:
                if p.default is None:
                    raise ValueError(f"missing '{p.name}'")
                values[p.name] = p.default
            if isinstance(values.get(p.name), Texture) and not p.texture:
                raise ValueError(f"{p.name}: {self.name}'s {p.name} cannot be a texture (the host "
                                 "derives constants from it)")
        # a texture is checked by its largest values
        bounds = {k: constant_of(v, self.kind_of(k), Texture.maximum) for k, v in values.items()}
        problem = self.check({k: np.atleast_2d(v) if np.ndim(v) else np.atleast_1d(v)
                              for k, v in bounds.items()})
        if problem:
            raise ValueError(problem)
        return values

    def slots(self) -> dict:
        """{name: slot} of every slotted parameter and derived slot, which tag_source makes the
        kernels' accessors of."""
        return {**{p.name: p.slot for p in self.params if p.slot}, **{d.name: d.slot for d in self.derived}}

    def kind_of(self, name: str) -> str:
        return next((p.kind for p in self.params if p.name == name), "number")

    def check(self, values: dict) -> str | None:
        """A problem with a combination of values (every parameter present), or None."""
        return None

    variant_defines: tuple = ()   # every define defines() may give

    def defines(self, rows: np.ndarray) -> tuple:
        """The kernel defines that MATERIAL rows of this type need (code of variants that
        scenes without them do not compile in)."""
        return ()

    def transmits(self, values: dict) -> bool:
        """Whether a material of these parameters (textures among them) is seen from both sides:
        its type's flag, or for a type that transmits by its parameters (principled), theirs."""
        return bool(self.flags & TRANSMISSIVE)

    def row_flags(self, values: dict, n: int) -> np.ndarray:
        """The flags of n rows of these values: the type's, and DELTA for rows whose every lobe
        is a delta where the type's are not always (a layered material of smooth layers)."""
        return np.full(n, self.flags, np.int32)

    def pack(self, values: dict, rows: np.ndarray):
        """Writes each slotted parameter into its slot; a type with derived slots writes those too."""
        for p in self.params:
            if p.slot:
                write_slot(rows, p.slot, values[p.name])

    def unpack(self, row) -> dict:
        """The slotted parameters of one row; a type whose others derive from its slots adds them."""
        return {p.name: read_slot(row, p.slot).copy() if p.kind == "color" else
                (bool if p.kind == "bool" else float)(read_slot(row, p.slot)) for p in self.params if p.slot}

    def continuation(self, values: dict) -> np.ndarray:
        """The probability with which the report's Russian roulette goes on from this material:
        an estimate of its albedo, at most 1. Any value in (0, 1] keeps the estimate unbiased."""
        return np.ones(len(next(iter(values.values()))))

