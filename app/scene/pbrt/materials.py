"""pbrt-v4's materials and textures, mapped onto pathtrace's (app/materials, app/textures) as
pbrt-v4 means them: roughness remapped as pbrt remaps it, texture coordinates flipped as pbrt's
image lookups flip them, colours from spectra (app/scene/spectra.py). What pathtrace does not have yet
is approximated by its nearest material, with one warning each (docs/pbrt.md)."""

from dataclasses import replace

import numpy as np

from pathtrace.errors import UserError, warn
from pathtrace.scene.known_names import refuse_unknown_type
from pathtrace.materials import BSDFS, Material
from pathtrace.materials.bsdf import TRANSMISSIVE
from pathtrace.materials.surface import PBRT_MAPS, from_pbrt
from pathtrace.materials.table import blend, transmits
from pathtrace.parameters import by_format, format_names, missing, out_of_range, read
from pathtrace.textures import TEXTURES, Texture
from pathtrace.textures.texture import PBRT_MAPPING
from pathtrace.textures.bitmap import read_image

BSDFS_BY_NAME = by_format(BSDFS.values(), "pbrt")
# the parameter types of the array kinds (app/parameters.py)
ARRAYS = {"points": ("point3",), "normals": ("normal", "normal3"), "pairs": ("point2",), "integers": ("integer",),
          "numbers": ("float",)}
TEXTURES_BY_NAME = by_format(TEXTURES.values(), "pbrt")



def make(kind, values, where) -> Material:
    """A Material of pathtrace's type `kind`, its values completed and checked by the type."""
    try:
        # pbrt's reflecting BSDFs reflect on both sides (Mitsuba's, which pathtrace's follow,
        # on the front only); glass is two-sided by its own nature
        complete = BSDFS[kind].complete(values)
    except ValueError as e:
        raise UserError(f"{where}: {e}") from None
    error = out_of_range(BSDFS[kind].params, complete)     # the TOML reader's ranges (a reflectance in [0, 1])
    if error:
        name, _, text = str(error).partition(": ")
        pbrt_name = next(p.pbrt or p.pbrt_from for p in BSDFS[kind].params if p.name == name)
        raise UserError(f"{where}: the {kind} material's {name}" + (f" (from '{pbrt_name}')" if pbrt_name else "")
                        + f" {text}")
    return Material(kind, complete, twosided=not BSDFS[kind].flags & TRANSMISSIVE)


class MaterialMapper:
    """The reader's named textures and materials, and the mapping of pbrt's onto pathtrace's."""

    def __init__(self, reader):
        self.reader = reader
        self.textures = {}          # name: Texture or float
        self.float_textures = {}
        self.images = {}

    # -- textures --

    def texture_input(self, params, name, default, float_texture=False):
        """A material's or texture's input: a texture by name, or a constant colour (or float)."""
        if params.type_of(name) == "texture":
            ref = params.string(name)
            table = self.float_textures if float_texture else self.textures
            if ref not in table:
                other = self.textures if float_texture else self.float_textures
                if ref in other:
                    params.fail(name, f"texture '{ref}' is a {'spectrum' if float_texture else 'float'} texture")
                params.fail(name, f"no texture named '{ref}'")
            return table[ref]
        if float_texture:
            return params.float(name, default)
        return params.spectrum(name, default)

    def parameter(self, params, p, name):
        """The value of the declared parameter p (app/parameters.py) that the parameter `name`
        gives, by p's kind (its pbrt_kind where set; a colour from a spectrum as p.spectrum
        says); None where it is not given."""
        ptype = params.type_of(name)
        if ptype is None:
            return None
        if p.texture and ptype == "texture":
            return self.texture_input(params, name, None, p.kind == "number")
        if p.kind == "color":
            return params.spectrum(name, None, p.spectrum)
        if p.kind == "image":        # pbrt-v4's empty file name is none
            file = params.string(name)
            return read_image(self.reader.resolve(file), params.where(name), p.raw, self.images) if file else None
        if p.kind in ARRAYS:
            return params.get(name, ARRAYS[p.kind], 0)
        read = {"number": params.float, "integer": params.int, "bool": params.bool, "string": params.string,
                "name": params.string, "point": params.point, "vector": params.point}[p.pbrt_kind or p.kind]
        return read(name)

    def define_texture(self, name, kind, cls, params, where):
        """Texture "name" "spectrum"|"float" "class" ..."""
        if kind not in ("spectrum", "float"):
            raise UserError(f"{where}: a texture is \"spectrum\" or \"float\", got {kind!r}")
        is_float = kind == "float"
        value = self._texture(cls, params, is_float, where)
        (self.float_textures if is_float else self.textures)[name] = value

    def _texture(self, cls, params, is_float, where):
        """A texture of the type that declares pbrt-v4's `cls` (its parameters' pbrt-v4 names,
        its from_pbrt): its colour inputs float textures (or numbers) in a float texture, and
        those pbrt-v4 reads as float textures; its image read as its `raw` (encoding) says."""
        kind = TEXTURES_BY_NAME.get(cls)
        if kind is None:
            return self._unknown_texture(cls, params, is_float, where)

        def get(p, name):
            if p.kind == "color":
                return self.texture_input(params, name, None, is_float or p.name in kind.pbrt_floats)
            return self.reader.resolve(params.string(name)) if p.kind == "image" and params.type_of(name) \
                else self.parameter(params, p, name)
        given = {}
        try:
            values = read(kind.parameters + kind.format_only + (PBRT_MAPPING if kind.pbrt_uv else ()), "pbrt", get, given)
            absent = missing(kind.parameters, values)
            if absent:
                raise UserError(f"{where}: {'an' if cls[0] in 'aeiou' else 'a'} {cls} needs a {absent[0].pbrt}")
            for p in kind.parameters:
                if p.kind == "image":
                    values[p.name] = read_image(values[p.name], f"{where}: {p.pbrt}", values["raw"], self.images)
            if kind.pbrt_uv:
                values["to_uv"] = kind.pbrt_to_uv(given, lambda text: warn(f"{where}: {text}"))
            texture = kind.from_pbrt(values, given, lambda text: warn(f"{where}: {text}"))
        except ValueError as e:
            self.fail(params, where, e)
        if is_float or isinstance(texture, Texture):
            return texture
        return np.broadcast_to(np.asarray(texture, np.float64), 3).copy()

    def _unknown_texture(self, cls, params, is_float, where):
        """A constant for a texture pathtrace has not: a bilerp's the mean of its constant
        corners, another's 0.5, with a warning."""
        if cls == "bilerp":
            corners = [self.texture_input(params, k, d, is_float)
                       for k, d in (("v00", 0.0), ("v01", 1.0), ("v10", 0.0), ("v11", 1.0))]
            mean = np.mean([np.asarray(c, np.float64) for c in corners if not isinstance(c, Texture)] or [0.5], axis=0)
            value = float(np.mean(mean)) if is_float else np.broadcast_to(mean, 3).copy()
            warn(f"{where}: pathtrace has no bilerp texture; it uses the mean of its constant corners, "
                 f"{', '.join(f'{v:.3g}' for v in np.atleast_1d(value))}")
            return value
        warn(f"{where}: pathtrace has no {cls} texture; it uses a constant 0.5 instead")
        return 0.5 if is_float else np.full(3, 0.5)

    # -- materials --

    @staticmethod
    def fail(params, where, error: ValueError, declared=()):
        """A type's ValueError ("<name>: <problem>", the name pbrt-v4's or that of one of the
        `declared` Parameters) as one line naming the parameter's file:line, or the directive's
        (`where`) where the directive does not give it (or there is none: pbrt-v4's default camera)."""
        name, _, problem = str(error).partition(": ")
        name = format_names(declared, "pbrt").get(name, name)
        if params is not None and name in params.params:
            params.fail(name, problem)
        raise UserError(f"{where}: {error}") from None

    def material(self, kind, params, where) -> Material | None:
        """The Material of a pbrt material, or None for `interface` (and "" / "none"): no
        surface, only a boundary between media; with its normalmap or displacement (surface.py:
        PBRT_MAPS), which a mix's materials carry (MixMaterial reads none)."""
        material = self._material(kind, params, where)
        if material is None or kind == "mix":
            return material
        given = {}
        read(PBRT_MAPS, "pbrt", lambda p, name: self.parameter(params, p, name), given)
        return replace(material, **from_pbrt(given, lambda name, text: warn(f"{params.where(name)}: {text}")))

    def _material(self, kind, params, where) -> Material | None:
        if kind in ("interface", "", "none"):
            return None
        if kind == "mix":
            return self._mix(params, where)
        if kind in BSDFS_BY_NAME:         # the types that declare their pbrt-v4 parameters
            bsdf, given = BSDFS_BY_NAME[kind], {}
            values = read(bsdf.params + bsdf.format_only, "pbrt", lambda p, name: self.parameter(params, p, name), given)
            # the numbers a file gives as they are checked at their own lines (a layer's walks)
            error = out_of_range([p for p in bsdf.params if p.kind == "number" and p.pbrt and not p.from_pbrt], values)
            if error:
                self.fail(params, where, error, bsdf.params)
            try:
                chosen = bsdf.from_pbrt(values, given, lambda text: warn(f"{where}: {text}"))
            except ValueError as e:
                self.fail(params, where, e)
            return None if chosen is None else make(*chosen, where)
        refuse_unknown_type("pbrt", "material", kind, where)
        warn(f"{where}: pathtrace has no {kind} material; it uses a diffuse one of albedo 0.5")
        return make("diffuse", {"rho_d": np.full(3, 0.5)}, where)

    def _mix(self, params, where):
        """pbrt-v4's mix: materials[1] with probability `amount` (a number or a float texture),
        as pathtrace's blendbsdf chooses its second component; an `interface` in it (no
        surface) leaves the other alone, with a warning."""
        names = params.get("materials", ("string",), 2)
        if names is None:
            raise UserError(f'{where}: a mix material needs "string materials" [ "first" "second" ]')
        parts = [self.reader.named_material(n, where) for n in names]
        values = read(BSDFS["blendbsdf"].params, "pbrt", lambda p, name: self.parameter(params, p, name))
        if any(p is None for p in parts):
            other = next((p for p in parts if p is not None), None)
            warn(f"{where}: pathtrace cannot mix a surface with an interface; it uses the other material alone")
            return other
        try:
            mixed = blend(values.get("weight"), parts)
        except ValueError as e:
            self.fail(params, where, e, BSDFS["blendbsdf"].params)
        mixed.twosided = not transmits(mixed)
        return mixed
