"""pbrt-v4's graphics state and the directives that only change it (pbrt-v4's file format,
"pbrt-v4 User's Guide", and its src/pbrt/parser.cpp and scene.cpp): the current transform
(CTM) and its named coordinate systems, the attribute and transform stacks, ReverseOrientation,
the MediumInterface, Include and Import, object definitions, and the directives pathtrace reads
and ignores. `Transform`/`ConcatTransform` take 16 numbers in column-major order; `Rotate`,
`Scale`, `Translate`, `LookAt` post-multiply the CTM. The pbrt reader (reader.py) is a
GraphicsStateDirectives, which reads the files that Include names (parse_file)."""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pathtrace.errors import UserError, cut, warn
from pathtrace.scene import transform
from pathtrace.scene.pbrt.tokens import numbers, parameters, string

MAX_FILE_BYTES = 4 << 30
MAX_INCLUDE_DEPTH = 16
# Include directives read in all: a file included from many places counts each time, so that
# a tree of includes (12 wide and 8 deep: 470 million reads) is refused at once, not read for ever
MAX_INCLUDES = 4096


@dataclass
class GraphicsState:
    ctm: np.ndarray = field(default_factory=lambda: np.eye(4))
    reverse: bool = False
    material: object = "default"          # a Material, None (an interface), or "default"
    area_light: object = None             # (ParamList, where) of an AreaLightSource
    media: tuple = ("", "")               # MediumInterface: the inside and outside media's names

    def copy(self):
        # not dataclasses.replace, which costs 25 us: an attribute block per shape is common;
        # the ctm shared, as the reader replaces it and never changes it in place
        return GraphicsState(self.ctm, self.reverse, self.material, self.area_light, self.media)


class GraphicsStateDirectives:
    """The graphics state of a pbrt file being read, and the directives that change only it."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.folder = self.path.parent
        self.state = GraphicsState()
        self.stack = []                   # saved states of AttributeBegin / TransformBegin
        self.in_world = False             # past WorldBegin: the scene's block, not the options' (check_block)
        self.named_systems = {}
        self.including = []
        self.includes = 0                 # Include directives read so far
        self.inverted = (None, None)      # (the bytes of a transform, its inverse): singular()
        self.warned = set()
        self.objects = {}                 # ObjectBegin name: its builder object
        self.current_object = None
        self.object_shapes = {}           # ObjectBegin name: its shapes, until it is instanced

    def resolve(self, name: str) -> Path:
        p = Path(name)
        return p if p.is_absolute() else self.folder / p

    def once(self, key, message):
        if key not in self.warned:
            self.warned.add(key)
            warn(message)

    def inverse(self, where: str, what: str) -> np.ndarray:
        """The inverse of the current transform, which `what` needs; an error naming the line
        where it is singular (a Scale of 0, or factors whose product underflows to 0): pbrt-v4
        goes on with an inverse of NaNs there, which would render nothing meaningful."""
        inverse = None if self.singular() else self.inverted[1]
        if inverse is None:
            raise UserError(f"{where}: {what} needs the current transform's inverse, but the transform is singular")
        return inverse

    def singular(self) -> bool:
        """Whether the current transform is singular; its inverse kept, with the transform's
        bytes, for the shapes that follow under the same transform."""
        key = self.state.ctm.tobytes()
        if self.inverted[0] != key:
            self.inverted = key, _inverse(self.state.ctm)
        return self.inverted[1] is None

    def concat(self, m):
        self.state.ctm = self.state.ctm @ m

    def _transform(self, tokens, offset, concat):
        m = numbers(tokens, 16, "Transform").reshape(4, 4).T
        if np.any(m[3] != [0, 0, 0, 1]):      # (a singular one flattens what follows: singular())
            tokens.fail(offset, "a projective transform (its last row must be 0 0 0 1)")
        self.state.ctm = self.state.ctm @ m if concat else m

    def _lookat(self, tokens, offset):
        v = numbers(tokens, 9, "LookAt")
        try:
            self.concat(np.linalg.inv(transform.look_at(v[:3], v[3:6], v[6:])))
        except ValueError as e:
            tokens.fail(offset, f"LookAt: {e}")

    def _attribute_begin(self, tokens, offset, directive="AttributeBegin"):
        """The graphics state saved, with where its block began (the stack's entries: the
        directive, the state, file:line), for its end or the file's (reader.read)."""
        self.stack.append((directive, self.state.copy(), tokens.where(offset)))

    def _attribute_end(self, tokens, offset, directive="AttributeEnd"):
        begun = ("ObjectBegin",) if directive == "ObjectEnd" else ("AttributeBegin", "TransformBegin")
        if not self.stack or self.stack[-1][0] not in begun:
            open_block = f" (the block open is the {self.stack[-1][0]} of {self.stack[-1][2]})" if self.stack else ""
            tokens.fail(offset, f"{directive} without {begun[0]}{open_block}")
        self.state = self.stack.pop()[1]

    def _transform_begin(self, tokens, offset):
        # pbrt-v4's parser takes TransformBegin/End as AttributeBegin/End, the whole graphics
        # state saved (src/pbrt/parser.cpp), with a warning that they are deprecated
        self.once("TransformBegin", f"{tokens.where(offset)}: TransformBegin/End are deprecated in pbrt-v4, "
                                    "which takes them as AttributeBegin/End; so does pathtrace")
        self._attribute_begin(tokens, offset, "TransformBegin")

    def _world_begin(self, tokens, offset):
        self.in_world = True
        self.state.ctm = np.eye(4)
        self.named_systems["world"] = np.eye(4)

    def _medium_interface(self, tokens, offset):
        """MediumInterface "inside" "outside" (one name: both sides)."""
        inside = string(tokens, "MediumInterface")
        outside = inside
        if tokens.peek()[0] == "string" and " " not in tokens.peek()[1]:
            outside = tokens.next()[1]
        self.state.media = (inside, outside)

    def _coordinate_system(self, tokens, offset):
        self.named_systems[string(tokens, "CoordinateSystem")] = self.state.ctm.copy()

    def _coord_sys_transform(self, tokens, offset):
        name = string(tokens, "CoordSysTransform")
        if name not in self.named_systems:
            tokens.fail(offset, f"no coordinate system named '{cut(name)}'")
        self.state.ctm = self.named_systems[name].copy()

    def _include(self, tokens, offset):
        name = string(tokens, "Include")
        self.includes += 1
        if self.includes > MAX_INCLUDES:
            tokens.fail(offset, f"more than {MAX_INCLUDES} Includes in all (each time a file is included counts)")
        self.parse_file(self.resolve(name), tokens.where(offset))

    def _ignored(what, instead, count=0, takes_params=False):
        def handler(self, tokens, offset):
            for _ in range(count):
                string(tokens, what)
            if takes_params:
                parameters(tokens)
            self.once(what, f"{tokens.where(offset)}: {what} is not supported; ignored ({instead})")
        return handler

    def _option(self, tokens, offset):
        parameters(tokens)
        self.once("Option", f"{tokens.where(offset)}: Option is not supported; ignored")

    def _transform_times(self, tokens, offset):
        numbers(tokens, 2, "TransformTimes")

    def _active_transform(self, tokens, offset):
        kind, value, at = tokens.next()
        if value not in ("All", "StartTime", "EndTime"):
            tokens.fail(at, "ActiveTransform takes All, StartTime or EndTime")
        if value != "All":
            self.once("motion", f"{tokens.where(offset)}: pathtrace has no motion blur; it uses the start transform")

    def _object_begin(self, tokens, offset):
        name = string(tokens, "ObjectBegin")
        if self.current_object is not None:
            tokens.fail(offset, "ObjectBegin inside another ObjectBegin")
        self._attribute_begin(tokens, offset, "ObjectBegin")
        self.current_object = name
        # its shapes are kept as read and made at its first ObjectInstance: a file of 100,000
        # objects never instanced costs their reading only (pbrt-v4 reads one in under a second)
        self.objects[name] = None
        self.object_shapes[name] = []

    def _object_end(self, tokens, offset):
        if self.current_object is None:
            tokens.fail(offset, "ObjectEnd without ObjectBegin")
        self._attribute_end(tokens, offset, "ObjectEnd")
        self.current_object = None

    def _reverse_orientation(self, tokens, offset):
        self.state.reverse = not self.state.reverse


def _inverse(m: np.ndarray):
    """m's inverse, or None where m is singular (or its inverse overflows)."""
    try:
        inverse = np.linalg.inv(m)
    except np.linalg.LinAlgError:
        return None
    return inverse if np.all(np.isfinite(inverse)) else None


def _three(what, make):
    def handler(self, tokens, offset):
        self.concat(make(numbers(tokens, 3, what)))
    return handler


def _rotate(self, tokens, offset):
    v = numbers(tokens, 4, "Rotate")
    if np.linalg.norm(v[1:]) == 0:
        tokens.fail(offset, "Rotate: the axis is zero")
    self.concat(transform.rotation(v[1:], v[0]))


# The directives pbrt-v4 takes in one block of the file only, before WorldBegin (the options)
# or after it (the scene), and refuses in the other (src/pbrt/scene.cpp, BasicSceneBuilder:
# VERIFY_OPTIONS and VERIFY_WORLD)
OPTIONS_ONLY = frozenset(("Camera", "Sampler", "WorldBegin", "TransformTimes", "PixelFilter", "Film", "Accelerator",
                          "Integrator"))
WORLD_ONLY = frozenset(("ReverseOrientation", "AttributeBegin", "AttributeEnd", "LightSource", "Shape", "ObjectBegin",
                        "ObjectEnd", "ObjectInstance", "Texture", "Material", "MakeNamedMaterial", "NamedMaterial",
                        "AreaLightSource", "TransformBegin", "TransformEnd"))     # (the last two as AttributeBegin/End)


def check_block(reader, name: str, tokens, offset):
    """Refuses a directive in the block pbrt-v4 refuses it in, as pbrt-v4 words it."""
    if name in OPTIONS_ONLY and reader.in_world:
        tokens.fail(offset, f'options cannot be set inside the world block; "{name}" is not allowed '
                            "after WorldBegin (as in pbrt-v4)")
    if name in WORLD_ONLY and not reader.in_world:
        tokens.fail(offset, f'the scene description must be inside the world block; "{name}" is not allowed '
                            "before WorldBegin (as in pbrt-v4)")


STATE_DIRECTIVES = {
    "Identity": lambda self, tokens, offset: setattr(self.state, "ctm", np.eye(4)),
    "Translate": _three("Translate", transform.translation),
    "Scale": _three("Scale", transform.scaling),      # a zero factor flattens what follows: singular()
    "Rotate": _rotate,
    "LookAt": GraphicsStateDirectives._lookat,
    "Transform": lambda self, tokens, offset: self._transform(tokens, offset, False),
    "ConcatTransform": lambda self, tokens, offset: self._transform(tokens, offset, True),
    "CoordinateSystem": GraphicsStateDirectives._coordinate_system,
    "CoordSysTransform": GraphicsStateDirectives._coord_sys_transform,
    "TransformTimes": GraphicsStateDirectives._transform_times,
    "ActiveTransform": GraphicsStateDirectives._active_transform,
    "ReverseOrientation": GraphicsStateDirectives._reverse_orientation,
    "Accelerator": GraphicsStateDirectives._ignored("Accelerator", "pathtrace builds its own BVH", 1, True),
    "ColorSpace": GraphicsStateDirectives._ignored("ColorSpace", "pathtrace takes colours as linear sRGB", 1),
    "Option": GraphicsStateDirectives._option,
    "WorldBegin": GraphicsStateDirectives._world_begin,
    "WorldEnd": lambda self, tokens, offset: None,    # pbrt-v3's end, which pbrt-v4 refuses outside its formatter; taken
    "AttributeBegin": GraphicsStateDirectives._attribute_begin,
    "AttributeEnd": GraphicsStateDirectives._attribute_end,
    "TransformBegin": GraphicsStateDirectives._transform_begin,
    "TransformEnd": lambda self, tokens, offset: self._attribute_end(tokens, offset, "TransformEnd"),
    "Attribute": GraphicsStateDirectives._ignored("Attribute", "each directive uses its own parameters and pbrt-v4's defaults", 1, True),
    "MediumInterface": GraphicsStateDirectives._medium_interface,
    "ObjectBegin": GraphicsStateDirectives._object_begin,
    "ObjectEnd": GraphicsStateDirectives._object_end,
    "Include": GraphicsStateDirectives._include,
    "Import": GraphicsStateDirectives._include,
}
