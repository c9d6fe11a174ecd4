"""Reading Mitsuba 3 XML scenes (the subset docs/mitsuba.md lists) into the scene description
the TOML format also produces. Every problem names the file and line, e.g.
    cbox.xml:12: <float name="radius">: 'abc' is not a number
and what pathtrace cannot do (heterogeneous media, other integrators) is one warning line per
element saying what it does instead.

Files come from strangers, so the parser is expat with document type declarations refused (no
entity expansion, no external entities: what defusedxml guards against), and sizes are bounded:
the file, the element count, include depth, tessellation and the film."""

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np

from pathtrace import cameras
from pathtrace.cameras.camera import FileCamera, frame_of
from pathtrace.cameras.perspective import PerspectiveCamera, vertical_fov
from pathtrace.scene.environment import Environment
from pathtrace.errors import UserError, cut, short, warn
from pathtrace.filters import FILTERS, PixelFilter
from pathtrace import parameters
from pathtrace.lights import DELTA_LIGHTS
from pathtrace.materials import BSDFS, Material
from pathtrace.materials.bsdf import LUMINANCE, constant_of
from pathtrace.materials.table import blend, scaled_bump_map, transmits
from pathtrace.parameters import FRAME
from pathtrace.scene.media import Medium, MediumInterface
from pathtrace.scene import transform
from pathtrace.scene.description import Mesh, MeshFile, RenderSettings, Scene, SceneBuilder
from pathtrace.scene.known_names import Unread
from pathtrace.scene.validate import MAX_SIZE
from pathtrace.scene.meshes import (MAX_COORDINATE, MeshFiles, check_mesh, mitsuba_cube, mitsuba_rectangle, place_mesh,
                                    vertex_normals)
from pathtrace.shapes import SHAPES, Shape
from pathtrace.shapes.shape import MIN_DETERMINANT
from pathtrace.textures import TEXTURES, Texture, read_image

MAX_XML_BYTES = 64 << 20
MAX_ELEMENTS = 1_000_000   # in a file and its includes together, as MAX_XML_BYTES
MAX_NESTING = 64           # elements inside elements (a Mitsuba scene needs a handful)
MAX_INCLUDE_DEPTH = 8
LIGHTS_BY_NAME = parameters.by_format(DELTA_LIGHTS.values(), "mitsuba")
BSDFS_BY_NAME = parameters.by_format(BSDFS.values(), "mitsuba")
TEXTURES_BY_NAME = parameters.by_format(TEXTURES.values(), "mitsuba")


@dataclass
class Node:
    tag: str
    attrs: dict
    line: int
    file: Path
    children: list = field(default_factory=list)

    def where(self):
        """file:line: <tag key="value">, by the first of name, type and id it has."""
        key = next((k for k in ("name", "type", "id") if self.attrs.get(k)), None)
        label = f'<{cut(self.tag)} {key}="{cut(self.attrs[key])}">' if key else f"<{cut(self.tag)}>"
        return f"{self.file}:{self.line}: {label}"


def parse_xml(path: Path, budget: list = None, where: str = None) -> Node:
    """The element tree of one file, each element with its line; a malformed file is one
    UserError naming the line. budget: [bytes, elements] left for this file and the others of
    its scene (its includes), which it decreases; where: what names the file (an <include>)."""
    from pathtrace.io.files import check_regular_file, missing, shown
    budget = [MAX_XML_BYTES, MAX_ELEMENTS] if budget is None else budget
    try:
        os.stat(path)
    except FileNotFoundError:
        raise missing(path, "scene file", where) from None
    except OSError as e:
        raise UserError(f"{where or shown(path)}: cannot read the scene ({e.strerror})") from None
    check_regular_file(path, where or shown(path), "the scene file", budget[0])
    try:
        with open(path, "rb") as f:
            data = f.read(budget[0] + 1)
    except OSError as e:
        raise UserError(f"{path}: cannot read the scene ({e.strerror})") from None
    if len(data) > budget[0]:
        raise UserError(f"{path}: the scene and its includes are larger than {MAX_XML_BYTES >> 20} MB")
    budget[0] -= len(data)
    parser = expat.ParserCreate()
    stack = [Node("#document", {}, 0, path)]

    def refuse_dtd(*_):
        raise UserError(f"{path}:{parser.CurrentLineNumber}: document type declarations "
                        "(<!DOCTYPE>, <!ENTITY>) are not accepted in scene files")

    def start(tag, attrs):
        budget[1] -= 1
        if budget[1] < 0:
            raise UserError(f"{path}: the scene and its includes have more than {MAX_ELEMENTS} elements")
        if len(stack) > MAX_NESTING:
            raise UserError(f"{path}:{parser.CurrentLineNumber}: elements nest deeper than {MAX_NESTING}")
        node = Node(tag, attrs, parser.CurrentLineNumber, path)
        stack[-1].children.append(node)
        stack.append(node)

    def end(tag):
        stack.pop()

    parser.StartDoctypeDeclHandler = refuse_dtd
    parser.EntityDeclHandler = refuse_dtd
    parser.ExternalEntityRefHandler = refuse_dtd
    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        # the whole buffer at once: ParseFile feeds expat in blocks, and a token spread over
        # many blocks (a 20 MB comment) took time quadratic in its length (64 s)
        parser.Parse(data, True)
    except expat.ExpatError as e:
        raise UserError(f"{path}:{e.lineno}: not well-formed XML ({expat.ErrorString(e.code)})") from None
    except (LookupError, ValueError) as e:      # an encoding Python does not know
        raise UserError(f"{path}:1: the XML declaration's encoding cannot be read ({cut(str(e))})") from None
    roots = stack[0].children
    if len(roots) != 1 or roots[0].tag != "scene":
        raise UserError(f"{path}: not a Mitsuba scene (the root element must be <scene>)")
    return roots[0]


# --- property values ---------------------------------------------------------------------

class Props(dict):
    """An element's properties, {name: Node}, noting each name the reader looks up: once the
    scene is read, the reader refuses or warns of every property it never looked up
    (_Reader.warn_unread; Mitsuba 3 refuses them all: "unreferenced property", src/core/xml.cpp,
    instantiate_node)."""

    def __init__(self, node, items):
        super().__init__(items)
        self.node = node
        self.read = set()

    def get(self, name, default=None):
        self.read.add(name)
        return super().get(name, default)

    def __contains__(self, name):
        self.read.add(name)
        return super().__contains__(name)

    def __getitem__(self, name):
        self.read.add(name)
        return super().__getitem__(name)

    def ignore(self):
        """An element left out or replaced whole, with a warning of its own: its properties
        get no warnings more."""
        self.read.update(self.keys())

    def unread(self) -> list:
        return [node for name, node in self.items() if name not in self.read]


def _fail(node, problem):
    raise UserError(f"{node.where()}: {problem}")


def _refuse(props, node, error: ValueError, names: dict = None):
    """A type's ValueError ("<field>: <problem>") as one line naming the property's element
    (`names`: the Mitsuba name of a field of pathtrace's), or the element's where it has none."""
    field, sep, problem = str(error).partition(": ")
    field = (names or {}).get(field, field)
    _fail(props.get(field, node) if sep else node, str(error) if not sep else f"{field}: {problem}")


def _float(node, text, what="value"):
    try:
        value = float(text)
    except (TypeError, ValueError):
        _fail(node, f"{what} {short(text)} is not a number")
    if not math.isfinite(value) or abs(value) > 3.0e38:
        _fail(node, f"{what} {short(text)} is not a finite float32")
    return value


def _floats(node, text, what="value"):
    parts = [p for p in re.split(r"[,\s]+", (text or "").strip()) if p]
    return [_float(node, p, what) for p in parts]


def _vector(node):
    """<point>/<vector>/<translate>: value="x, y, z" or x= y= z= attributes."""
    if "value" in node.attrs:
        v = _floats(node, node.attrs["value"])
        if len(v) == 1:
            v = v * 3
        if len(v) != 3:
            _fail(node, f"value must be 1 or 3 numbers, got {short(node.attrs['value'])}")
        return np.array(v)
    return np.array([_float(node, node.attrs.get(k, "0"), k) for k in "xyz"])


def _color(node):
    """<rgb value="r, g, b"> or one grey value; <spectrum value="v"> as one value (a spectrum
    of wavelength:value pairs is averaged, with a warning)."""
    text = node.attrs.get("value", "")
    if node.tag == "spectrum" and ":" in text:
        pairs = [p.split(":") for p in re.split(r"[,\s]+", text.strip()) if p]
        if any(len(p) != 2 for p in pairs):
            _fail(node, f"a spectrum is wavelength:value pairs, got {short(text)}")
        values = [_float(node, v) for _, v in pairs]
        warn(f"{node.where()}: a sampled spectrum; pathtrace renders RGB and uses its mean, {np.mean(values):.4g}")
        return np.full(3, float(np.mean(values)))
    v = _floats(node, text)
    if len(v) == 1:
        v = v * 3
    if len(v) != 3:
        _fail(node, f"value must be 1 or 3 numbers, got {short(text)}")
    if min(v) < 0:
        _fail(node, f"a colour must not be negative, got {short(text)}")
    return np.array(v)


def _lookat(node):
    o, t, up = (np.array(_floats(node, node.attrs.get(k, d), k)) for k, d in
                (("origin", ""), ("target", ""), ("up", "0, 1, 0")))
    if len(o) != 3 or len(t) != 3 or len(up) != 3:
        _fail(node, "origin, target and up must be 3 numbers each")
    try:
        return transform.look_at(o, t, up)      # x is the image's left in Mitsuba's camera space
    except ValueError as e:
        _fail(node, str(e))


def _transform(node):
    """A <transform>'s operations in file order, each applied after the ones before it."""
    m = np.eye(4)
    for op in node.children:
        if op.tag == "translate":
            step = transform.translation(_vector(op))
        elif op.tag == "scale":
            if "value" in op.attrs:
                s = _floats(op, op.attrs["value"])
                s = s * 3 if len(s) == 1 else s
            else:
                s = [_float(op, op.attrs.get(k, "1"), k) for k in "xyz"]
            if len(s) != 3 or 0 in s:
                _fail(op, "scale must be 1 or 3 non-zero numbers")
            step = transform.scaling(s)
        elif op.tag == "rotate":
            axis = _vector(op) if "value" not in op.attrs else np.array(_floats(op, op.attrs["value"]))
            if len(axis) != 3 or not np.linalg.norm(axis) > 1e-30:
                _fail(op, "the rotation axis must be 3 numbers, not all (near) zero")
            step = transform.rotation(axis, _float(op, op.attrs.get("angle"), "angle"))
        elif op.tag == "matrix":
            v = _floats(op, op.attrs.get("value", ""))
            if len(v) not in (9, 16):
                _fail(op, f"a matrix has 9 or 16 numbers, got {len(v)}")
            step = np.eye(4)
            if len(v) == 9:
                step[:3, :3] = np.reshape(v, (3, 3))
            else:
                step = np.reshape(v, (4, 4))
            if abs(np.linalg.det(step[:3, :3])) < 1e-12 or not np.allclose(step[3], [0, 0, 0, 1]):
                _fail(op, "must be an invertible affine transform (last row 0 0 0 1)")
        elif op.tag == "lookat":
            step = _lookat(op)
        else:
            _fail(op, "unknown transform operation (translate, rotate, scale, matrix, lookat)")
        m = step @ m
        # the normals' matrix is the inverse transpose: it must exist in float64 and hold in float32
        det = np.linalg.det(m[:3, :3])
        if not (np.all(np.isfinite(m)) and np.abs(m).max() <= 3.0e38 and abs(det) > 1e-36):
            _fail(op, "the transform so far is singular or beyond float32 (a scale that underflows?)")
    return m


class _Reader:
    """One scene: defaults, named objects, and the description being built."""

    def __init__(self, path: Path):
        self.path = path
        self.budget = [MAX_XML_BYTES, MAX_ELEMENTS]   # bytes and elements left (parse_xml)
        self.defaults = {}
        self.named = {}             # id -> Node
        self.builder = SceneBuilder()
        self.groups = {}            # id(shapegroup Node) -> its object in the builder
        self.material_rows = {}     # id(bsdf Node) -> material row
        self.textures = {}          # id(texture Node) -> Texture, so that a shared one is one
        self.images = {}            # the images read (read_image's cache)
        self.camera = None
        self.settings = RenderSettings(width=768, height=576, spp=4)
        self.environment = None
        self.lights = []            # point, spot and directional emitters
        self.filter = None          # the film's rfilter
        self.max_depth, self.rr = 0, "throughput"
        self.media = []             # the scene's participating media
        self.medium_rows = {}       # id(medium Node) -> row of self.media
        self.camera_medium = -1
        self.mesh_files = MeshFiles()   # the obj and ply shapes' files, read ahead
        self.props = {}             # id(Node) -> its Props (properties())

    # -- properties of an element: {name: Node} after $substitution --

    def substitute(self, node):
        for k, v in node.attrs.items():
            if "$" in v:
                def value(m):
                    if m.group(1) not in self.defaults:
                        _fail(node, f"${m.group(1)} has no <default> value")
                    return self.defaults[m.group(1)]
                node.attrs[k] = re.sub(r"\$([A-Za-z_][A-Za-z0-9_]*)", value, v)

    def expand(self, node, depth=0):
        """Substitutes $names, splices <include>s and records <default>s, in file order."""
        out = []
        for child in node.children:
            self.substitute(child)
            if child.tag == "default":
                name = child.attrs.get("name")
                if not name or "value" not in child.attrs:
                    _fail(child, "needs name and value")
                self.defaults.setdefault(name, child.attrs["value"])
                continue
            if child.tag == "include":
                if depth >= MAX_INCLUDE_DEPTH:
                    _fail(child, f"includes nest deeper than {MAX_INCLUDE_DEPTH}")
                name = child.attrs.get("filename")
                if not name:
                    _fail(child, "needs a filename")
                included = parse_xml(child.file.parent / name, self.budget, child.where())
                out.extend(self.expand(included, depth + 1))
                continue
            child.children = self.expand(child, depth)
            out.append(child)
        return out

    def properties(self, node) -> Props:
        """The element's Props, one per element however often it is read."""
        if id(node) not in self.props:
            self.props[id(node)] = Props(node, {
                c.attrs["name"]: c for c in node.children
                if "name" in c.attrs and c.tag in ("float", "integer", "boolean", "string", "rgb", "spectrum", "point",
                                                   "vector", "transform", "texture", "ref", "bsdf", "volume")})
        return self.props[id(node)]

    def warn_unread(self):
        """The properties the reader never looked up: refused where Mitsuba 3's plugin does not
        know them either, else warned of, once per name and plugin in a file
        (app/scene/known_names.py). Nested BSDFs are their readers' (shapes and the BSDFs that
        wrap them take them by their place), and references and volumes, which Mitsuba 3 may
        take by their place too, are warned of, never refused."""
        unread = Unread("mitsuba")
        for props in self.props.values():
            node = props.node
            kind = node.attrs.get("type")
            for child in props.unread():
                if child.tag == "bsdf":
                    continue
                message = unread.check(child.where(), f"{node.tag} {kind}", f"{kind} {node.tag}".strip(),
                                       child.attrs["name"], str(child.file), refusable=child.tag not in ("ref", "volume"))
                if message:
                    warn(message)

    def value(self, node):
        """The value of a property element."""
        tag, text = node.tag, node.attrs.get("value")
        if tag == "float":
            return _float(node, text)
        if tag == "integer":
            try:
                return int(text)
            except (TypeError, ValueError):
                _fail(node, f"{short(text)} is not an integer")
        if tag == "boolean":
            if text not in ("true", "false"):
                _fail(node, f"must be true or false, got {short(text)}")
            return text == "true"
        if tag == "string":
            if text is None:
                _fail(node, "needs a value")
            return text
        if tag in ("rgb", "spectrum"):
            return _color(node)
        if tag in ("point", "vector"):
            return _vector(node)
        if tag == "transform":
            return _transform(node)
        _fail(node, "unexpected element here")

    def get(self, props, name, default=None, kinds=None):
        node = props.get(name)
        if node is None:
            return default
        if node.tag == "ref":
            node = self.resolve(node)
        if kinds and node.tag not in kinds:
            _fail(node, f"'{name}' must be a {' or '.join(kinds)}")
        return self.value(node)

    def color(self, props, name, default, textures=True):
        """A colour parameter: rgb, spectrum, float, or (where `textures`) a Texture; elsewhere a
        texture is replaced by its mean colour, with a warning."""
        node = props.get(name)
        if node is None:
            return np.broadcast_to(np.asarray(default, np.float64), 3).copy()
        if node.tag == "ref":
            node = self.resolve(node)
        if node.tag == "texture":
            texture = self.texture(node)
            if textures:
                return texture
            mean = texture.mean()
            warn(f"{node.where()}: a texture cannot stand here; pathtrace uses its mean colour "
                 f"({', '.join(f'{c:.3g}' for c in mean)})")
            return mean
        if node.tag == "float":
            return np.full(3, self.value(node))
        if node.tag not in ("rgb", "spectrum"):
            _fail(node, f"'{name}' must be a colour (rgb, spectrum, float) or a texture")
        return self.value(node)

    def texture(self, node) -> Texture:
        """The Texture of a <texture> element: bitmap (filename, raw, filter_type, wrap_mode,
        to_uv) or checkerboard (color0, color1, to_uv), with Mitsuba 3's defaults; another type
        is replaced by a constant grey of 0.5, with a warning."""
        if id(node) in self.textures:
            return self.textures[id(node)]
        kind = node.attrs.get("type")
        props = self.properties(node)
        params = {"to_uv": self.get(props, "to_uv", np.eye(4), ("transform",))}
        if kind in TEXTURES_BY_NAME:
            params.update(parameters.read(TEXTURES_BY_NAME[kind].parameters, "mitsuba",
                                          lambda p, name: self.parameter(props, p, name)))
            if kind == "bitmap" and "file" not in params:
                _fail(node, "a bitmap needs a filename")
        else:
            warn(f"{node.where()}: pathtrace has no {kind} texture; it uses a constant grey of 0.5 instead")
            props.ignore()
            kind, params = "constant", {"value": 0.5}
        try:
            params = TEXTURES[kind].complete(params)
        except ValueError as e:
            _fail(node, str(e))
        self.textures[id(node)] = Texture(kind, params, node.attrs.get("id"))
        return self.textures[id(node)]

    def check_reference_cycles(self):
        """Refuses a <ref> that leads back to an element it is inside (a bsdf or texture made of
        itself), which would recurse for ever; found by depth-first search without recursion."""
        refs = {}
        for name, node in self.named.items():
            found, todo = [], list(node.children)
            while todo:
                child = todo.pop()
                if child.tag == "ref" and child.attrs.get("id") in self.named:
                    found.append(child)
                todo.extend(child.children)
            refs[name] = found
        state = {}                       # id -> 1 on the current path, 2 done
        for root in self.named:
            if root in state:
                continue
            path, stack = [], [(root, iter(refs[root]))]
            state[root] = 1
            path.append(root)
            while stack:
                name, pending = stack[-1]
                ref = next(pending, None)
                if ref is None:
                    state[name] = 2
                    stack.pop()
                    path.pop()
                    continue
                target = ref.attrs["id"]
                if state.get(target) == 1:
                    cycle = path[path.index(target):] + [target]
                    _fail(ref, f"a reference cycle: {short(' -> '.join(cycle))}")
                if target not in state:
                    state[target] = 1
                    path.append(target)
                    stack.append((target, iter(refs[target])))

    def resolve(self, ref):
        target = self.named.get(ref.attrs.get("id"))
        if target is None:
            _fail(ref, f"no element has id {short(ref.attrs.get('id'))}")
        return target

    @staticmethod
    def declared_ids(nodes) -> dict:
        """id -> element, for elements at any depth: Mitsuba 3 registers the ids of nested
        elements too (a texture declared inside one BSDF and referred to by another)."""
        named, todo = {}, list(reversed(nodes))
        while todo:                       # depth first, in document order
            node = todo.pop()
            if "id" in node.attrs and node.tag != "ref":
                named.setdefault(node.attrs["id"], node)
            todo.extend(reversed(node.children))
        return named

    # -- the scene --

    def read(self) -> Scene:
        root = parse_xml(self.path, self.budget)
        self.substitute(root)
        version = root.attrs.get("version", "3.0.0")
        if not version.startswith(("2.", "3.")):
            warn(f"{root.where()}: version {version}; pathtrace reads Mitsuba 3 scenes")
        nodes = self.expand(root)
        self.named = self.declared_ids(nodes)
        self.check_reference_cycles()
        with MeshFiles(self.named_mesh_files(nodes)) as self.mesh_files:
            for node in nodes:
                if node.tag == "shape" and node.attrs.get("type") == "shapegroup":
                    continue                   # drawn where an instance refers to it
                if node.tag == "shape":
                    self.shape(node)
                elif node.tag == "sensor":
                    self.sensor(node)
                elif node.tag == "integrator":
                    self.integrator(node)
                elif node.tag == "emitter":
                    self.emitter(node)
                elif node.tag in ("bsdf", "texture", "medium"):
                    continue                   # used where referenced
                else:
                    warn(f"{node.where()}: not supported; pathtrace ignores it")
        if not (self.builder.spheres or self.builder.meshes or self.builder.shapes or self.builder.instance_object):
            raise UserError(f"{self.path}: the scene has no shapes pathtrace can render")
        self.warn_unread()
        settings = self.settings
        settings.max_depth, settings.russian_roulette = self.max_depth, self.rr
        settings.filter = self.filter or PixelFilter("gaussian")      # Mitsuba's default
        return self.builder.build(self.path.stem, camera=self.camera or self.default_camera(),
                                  environment=self.environment or Environment.constant((0, 0, 0)),
                                  settings=settings, source=str(self.path), lights=self.lights,
                                  media=self.media, camera_medium=self.camera_medium)

    def named_mesh_files(self, nodes) -> list:
        """The (path, where) of the obj and ply shapes' files, in document order, for MeshFiles
        to read ahead (a file name given otherwise than as a string is left to shape())."""
        found, todo = [], list(reversed(nodes))
        while todo:
            node = todo.pop()
            if node.tag == "shape" and node.attrs.get("type") in ("obj", "ply"):
                filename = self.properties(node).get("filename")
                if filename is not None and filename.tag == "string" and filename.attrs.get("value"):
                    found.append((node.file.parent / filename.attrs["value"], node.where()))
            todo.extend(reversed(node.children))
        return found

    def default_camera(self):
        """Mitsuba's default sensor: at the origin, looking down +z, fov 45 on x."""
        return PerspectiveCamera((0, 0, 0), (0, 0, 1), (0, 1, 0),
                                 vertical_fov(45.0, "x", self.settings.width, self.settings.height))

    def integrator(self, node):
        kind = node.attrs.get("type")
        props = self.properties(node)
        if kind in ("bdpt", "ptracer"):
            self.settings.integrator = kind        # Mitsuba 0.6's bdpt, Mitsuba 3's particle tracer
        elif kind not in ("path", "volpath", "prb", "prbvolpath"):
            warn(f"{node.where()}: pathtrace renders with its path tracer instead")
            props.ignore()          # that integrator's own settings: only max_depth and rr_depth are read
        max_depth = self.get(props, "max_depth", -1, ("integer",))
        if not -1 <= max_depth < 2**31:
            _fail(props["max_depth"], f"must be -1 (unlimited) to {2**31 - 1}, got {max_depth}")
        self.max_depth = 0 if max_depth == -1 else max_depth
        rr_depth = self.get(props, "rr_depth", 5, ("integer",))
        if max_depth == 0:
            _fail(props["max_depth"], "0 renders nothing; pathtrace needs 1 or more (or -1)")
        if rr_depth != 5:
            if max_depth > 0 and rr_depth >= max_depth:
                self.rr = "off"
            else:
                warn(f"{node.where()}: pathtrace starts Russian roulette at depth 5, not {rr_depth}")

    def sensor(self, node):
        kind = node.attrs.get("type")
        cls = cameras.registry.format_class("mitsuba", kind)
        if cls is None:
            names = sorted(c.mitsuba for c in cameras.CAMERAS.values() if c.mitsuba)
            _fail(node, f"pathtrace has the {', '.join(names)} sensors only")
        props = self.properties(node)
        for child in node.children:
            if child.tag == "film":
                self.film(child)
            elif child.tag == "sampler":
                count = self.get(self.properties(child), "sample_count", 4, ("integer",))
                if not 1 <= count <= 1 << 24:
                    _fail(child, f"sample_count must be in 1..{1 << 24}, got {count}")
                self.settings.spp = count
            elif child.tag == "medium" or (child.tag == "ref" and self.resolve(child).tag == "medium"):
                self.camera_medium = self.medium(child)       # Mitsuba 3: the sensor's one medium
        if self.filter is None:
            self.filter = PixelFilter("gaussian")     # Mitsuba's default
        m = self.get(props, "to_world", np.eye(4), ("transform",))
        frame = frame_of(m, x_right=False)        # Mitsuba's camera space has +x to the image's left
        sensor = FileCamera(lambda name, default=None, kind="float": self.get(props, name, default, (kind,)),
                            props.__contains__, lambda name, problem: _fail(props.get(name, node) if name else node,
                                                                           problem),
                            lambda text, name=None: warn(f"{node.where()}: {text}"), self.settings.width,
                            self.settings.height, m)
        camera = cls.from_mitsuba(sensor, **frame)
        try:
            camera.check()
        except ValueError as e:
            _refuse(props, node, e, {p.name: p.mitsuba for p in camera.parameters if p.mitsuba})
        self.camera = camera

    def film(self, node):
        props = self.properties(node)
        w = self.get(props, "width", 768, ("integer",))
        h = self.get(props, "height", 576, ("integer",))
        for name, v in (("width", w), ("height", h)):
            if not 1 <= v <= MAX_SIZE:
                _fail(props[name], f"must be in 1..{MAX_SIZE}, got {v}")
        self.settings.width, self.settings.height = w, h
        if node.attrs.get("type") not in ("hdrfilm", "specfilm", None):
            warn(f"{node.where()}: pathtrace writes the image format of the output file's name")
        # the output's format is its file name's (render -o), whatever these say; a specfilm's
        # channels are its sensitivity functions', and it has no pixel_format
        for name in ("file_format", "component_format") + (("pixel_format",) if node.attrs.get("type") != "specfilm" else ()):
            props.get(name)
        for child in node.children:
            if child.tag == "rfilter":
                self.filter = self.rfilter(child)

    def rfilter(self, node) -> PixelFilter:
        """Mitsuba's box, tent or gaussian filter (PixelFilter.from_mitsuba), or its gaussian for
        one of negative lobes."""
        props = self.properties(node)
        if node.attrs.get("type") not in FILTERS:
            props.ignore()
        try:
            return PixelFilter.from_mitsuba(node.attrs.get("type"), lambda name, default: self.get(
                props, name, default, ("float",)), lambda text: warn(f"{node.where()}: {text}"))
        except ValueError as e:
            _refuse(props, node, e)

    def emitter(self, node):
        kind = node.attrs.get("type")
        props = self.properties(node)
        if self.environment is not None and kind in Environment.mitsuba_plugins:
            warn(f"{node.where()}: a second environment; pathtrace keeps the first")
            props.ignore()
            return
        if kind in Environment.mitsuba_plugins:       # by its declared Mitsuba names, those this emitter has
            values = parameters.read([p for p in Environment.parameters if p.name in Environment.mitsuba_plugins[kind]],
                                     "mitsuba", lambda p, name: self.parameter(props, p, name))
            try:
                self.environment = Environment.from_mitsuba(kind, values, lambda: self.get(
                    props, "to_world", np.eye(4), ("transform",)), node.file.parent, node.where(), warn)
            except ValueError as e:
                _refuse(props, node, e)
        elif kind in LIGHTS_BY_NAME:
            self.lights.append(self.delta_light(node, kind, props))
        else:
            warn(f"{node.where()}: pathtrace has no {kind} emitters; it ignores this one")
            props.ignore()

    def delta_light(self, node, kind, props):
        """A delta light of pathtrace.lights by its declared Mitsuba names; a point or vector
        that the emitter places by its to_world (app/parameters.py: FRAME) is to_world's origin
        or +z, where Mitsuba's point, spot and directional emitters shine along local +z."""
        cls = LIGHTS_BY_NAME[kind]
        m = self.get(props, "to_world", np.eye(4), ("transform",))
        frame = {"point": m[:3, 3], "vector": m[:3, :3] @ [0, 0, 1.0]}
        values = parameters.read(cls.parameters, "mitsuba", lambda p, name: self.parameter(props, p, name))
        kinds = {p.name: p.kind for p in cls.parameters}
        values = {k: frame[kinds[k]] if v is FRAME else v for k, v in values.items()}
        for name, why in cls.unsupported.get("mitsuba", {}).items():
            if name in props:
                warn(f"{props[name].where()}: {why}; ignored")
        try:
            return cls.from_values(values)
        except ValueError as e:
            _refuse(props, node, e)

    def parameter(self, props, p, name):
        """The value of the declared parameter p (app/parameters.py) that the property `name`
        gives, by p's kind; None where the element has no such property."""
        if name not in props:
            return None
        if p.kind == "color":
            return self.color(props, name, None, textures=p.texture)
        c = props[name]
        target = self.resolve(c) if c.tag == "ref" else c
        if p.texture and target.tag == "texture":
            return self.texture(target)
        if p.kind == "image":
            return read_image(props.node.file.parent / self.get(props, name, kinds=("string",)), c.where(),
                              self.get(props, "raw", False, ("boolean",)), self.images)
        kinds = {"number": ("float",), "integer": ("integer",), "bool": ("boolean",), "string": ("string",),
                 "name": ("string",), "point": ("point", "vector"), "vector": ("vector", "point")}[p.kind]
        if p.kind == "number" and getattr(p, "names", None) and target.tag == "string":
            kinds = ("string",)          # a named value (an IOR's name), which the type resolves
        return self.get(props, name, kinds=kinds)

    # -- materials --

    def material_row(self, bsdf, emission):
        """The material row of a shape's <bsdf> or <ref> and its area emitter's radiance; shapes
        that share a BSDF and emit nothing share a row. Without a <bsdf>, Mitsuba 3 gives a shape
        a diffuse BSDF of reflectance 0.5, and an emitting one a black BSDF: a lamp then reflects
        nothing, which in the tests' scenes is 0.2 % of what the floor below it receives."""
        target = self.resolve(bsdf) if bsdf is not None and bsdf.tag == "ref" else bsdf
        key = id(target)
        if emission is None and key in self.material_rows:
            return self.material_rows[key]
        if bsdf is not None:
            material = self.material(bsdf)
        else:
            material = Material("diffuse", {"rho_d": np.full(3, 0.0 if emission is not None else 0.5)})
        if emission is not None:
            material.emission = emission
            return self.builder.material(material)
        name = target.attrs.get("id") if target is not None else None
        self.material_rows[key] = self.builder.materials.add(material, name)
        return self.material_rows[key]

    def material_node(self, node):
        """The <bsdf> a shape's <bsdf> or <ref> stands for."""
        return self.resolve(node) if node.tag == "ref" else node

    def material(self, node) -> Material:
        """The Material of a <bsdf> (or <ref> to one)."""
        if node.tag == "ref":
            node = self.resolve(node)
            if node.tag != "bsdf":
                _fail(node, "a shape's <ref> must name a <bsdf>")
        kind = node.attrs.get("type")
        props = self.properties(node)
        if kind == "twosided":
            m = self.nested_material(node, named=True)
            if transmits(m):
                _fail(node, f"a twosided BSDF cannot hold a {m.type}: it transmits (Mitsuba 3 refuses it too)")
            m.twosided = True
            return m
        if kind == "blendbsdf":
            return self.blend(node, props)
        if kind == "mask":
            m = self.nested_material(node)
            m.opacity = self.opacity(props, node)
            return m
        if kind in ("bumpmap", "normalmap"):
            return self.mapped_material(node, kind, props)
        if kind in BSDFS_BY_NAME:
            return self.mitsuba_material(node, kind, props)
        albedo = self.color(props, "base_color", None, False) if "base_color" in props else \
            self.color(props, "reflectance", 0.5, False) if "reflectance" in props else np.full(3, 0.5)
        albedo = np.clip(albedo, 0, 1)
        props.ignore()
        warn(f"{node.where()}: not supported; pathtrace uses a diffuse BSDF of albedo "
             f"{', '.join(f'{c:.3g}' for c in albedo)}")
        return Material("diffuse", {"rho_d": albedo})

    def nested_material(self, node, named=False) -> Material:
        """The Material of the BSDF a wrapper (twosided, mask, bumpmap, normalmap) holds: its
        first nested <bsdf> or <ref>, one of a name too where `named`."""
        inner = [c for c in node.children if c.tag in ("bsdf", "ref") and (named or "name" not in c.attrs)]
        if not inner:
            _fail(node, "needs a nested <bsdf>")
        return self.material(inner[0])

    def blend(self, node, props) -> Material:
        """A `blendbsdf`: its two nested BSDFs, the second taken with probability `weight` (a
        number or a texture; 0.5)."""
        inner = [c for c in node.children if c.tag in ("bsdf", "ref") and c.attrs.get("name") != "weight"]
        if len(inner) != 2:
            _fail(node, f"needs two nested BSDFs, got {len(inner)}")
        weight = self.parameter(props, next(p for p in BSDFS["blendbsdf"].params if p.name == "weight"), "weight")
        try:
            return blend(0.5 if weight is None else weight, tuple(self.material(c) for c in inner))
        except ValueError as e:
            _refuse(props, node, e)

    def mapped_material(self, node, kind, props):
        """A `normalmap` (its texture `normalmap`) or `bumpmap` (its one texture, times `scale`)
        around a nested BSDF."""
        m = self.nested_material(node)
        maps = [c for c in node.children if c.tag == "texture" or (c.tag == "ref" and "name" in c.attrs)]
        if kind == "normalmap":
            maps = [c for c in maps if c.attrs.get("name") == "normalmap"]
        if not maps:
            _fail(node, 'needs a <texture name="normalmap">' if kind == "normalmap" else "needs a <texture>")
        if "name" in maps[0].attrs:          # the map is taken by its place, whatever its name
            props.read.add(maps[0].attrs["name"])
        target = self.resolve(maps[0]) if maps[0].tag == "ref" else maps[0]
        if target.tag != "texture":
            _fail(maps[0], "must be a texture")
        texture = self.texture(target)
        if m.normal_map is not None or m.bump_map is not None:
            warn(f"{node.where()}: a {kind} around another map; pathtrace applies the inner one only")
            return m
        if kind == "normalmap":
            m.normal_map = texture
            return m
        try:
            m.bump_map = scaled_bump_map(texture, self.get(props, "scale", 1.0, ("float",)))
        except ValueError as e:
            _fail(target, str(e))
        return m

    def opacity(self, props, node):
        """A mask's `opacity` (Mitsuba's default 0.5): a number in [0, 1] or a texture, whose
        luminance is the probability that a ray meets the surface."""
        value = self.color(props, "opacity", 0.5)
        if isinstance(value, Texture):
            low, high = value.minimum(), value.maximum()
        else:
            low = high = value
        if np.min(low) < 0 or np.max(high) > 1:
            _fail(props.get("opacity", node), "an opacity must lie in [0, 1]")
        return value if isinstance(value, Texture) else float(np.dot(value, LUMINANCE))

    def mitsuba_material(self, node, kind, props):
        """A material type of pathtrace's that Mitsuba 3 has, by its declared Mitsuba names
        (app/materials); Mitsuba's anisotropic roughness is alpha_u (pathtrace's alpha) and
        alpha_v, both required (its MicrofacetDistribution refuses one without the other)."""
        bsdf = BSDFS_BY_NAME[kind]
        values = parameters.read(bsdf.params, "mitsuba", lambda p, name: self.parameter(props, p, name))
        if any(p.name == "alpha_v" for p in bsdf.params) and ("alpha_v" in values or "alpha_u" in props):
            if "alpha" in props or "alpha_u" not in props or "alpha_v" not in props:
                _fail(node, "give alpha, or alpha_u and alpha_v, not a mixture")
            values["alpha"] = self.parameter(props, next(p for p in bsdf.params if p.name == "alpha"), "alpha_u")
        if "distribution" in values:
            props.get("sample_visible")      # pathtrace samples visible normals always (kernels/microfacet.cl)
        for p in bsdf.params:        # the range of what the file gave (the TOML reader's Param bounds)
            if p.kind in ("name", "bool") or p.name not in values or isinstance(values[p.name], str):
                continue
            low = np.asarray(constant_of(values[p.name], p.kind, Texture.minimum), np.float64)
            high = np.asarray(constant_of(values[p.name], p.kind, Texture.maximum), np.float64)
            if np.any(low < p.low) or (p.high is not None and np.any(high > p.high)):
                bound = f"[{p.low}, {p.high}]" if p.high is not None else f"at least {p.low}"
                _fail(props.get(p.mitsuba, node), f"{'an' if p.mitsuba[0] in 'aeiou' else 'a'} {p.mitsuba} must lie in {bound}")
        try:
            values = bsdf.complete(values)
        except ValueError as e:
            _fail(node, str(e))
        return Material(bsdf.name, values)

    # -- media --

    def medium(self, node) -> int:
        """The row of a <medium> (or a <ref> to one) in the scene's media: Mitsuba 3's
        `homogeneous` (sigma_t and albedo, constant, times scale) with an `isotropic` or `hg`
        phase function."""
        if node.tag == "ref":
            node = self.resolve(node)
            if node.tag != "medium":
                _fail(node, "a medium's <ref> must name a <medium>")
        if id(node) in self.medium_rows:
            return self.medium_rows[id(node)]
        kind = node.attrs.get("type")
        if kind != "homogeneous":
            _fail(node, f"pathtrace has homogeneous media only, not {short(kind)}")
        props = self.properties(node)
        for name in ("albedo", "sigma_t"):
            if name in props and props[name].tag == "volume":
                _fail(props[name], f"{name}: pathtrace's media are homogeneous; give a float or an rgb")
        props.get("has_spectral_extinction")    # spectral variants' choice; pathtrace is RGB
        if not self.get(props, "sample_emitters", True, ("boolean",)):
            warn(f"{props['sample_emitters'].where()}: pathtrace samples emitters in every medium")
        values = parameters.read(Medium.parameters, "mitsuba", lambda p, name: self.parameter(props, p, name))
        for phase in (c for c in node.children if c.tag == "phase"):
            phase_props = self.properties(phase)
            if phase.attrs.get("type") == "hg":
                values["g"] = self.get(phase_props, "g", 0.8, ("float",))     # Mitsuba 3's default
            elif phase.attrs.get("type") != "isotropic":
                phase_props.ignore()
                warn(f"{phase.where()}: pathtrace has no {phase.attrs.get('type')} phase function; "
                     "it scatters isotropically instead")
        try:
            medium = Medium.from_values(node.attrs.get("id") or f"medium {len(self.media)}", values)
        except ValueError as e:
            _refuse(props, node, e)
        self.media.append(medium)
        self.medium_rows[id(node)] = len(self.media) - 1
        return self.medium_rows[id(node)]

    # -- shapes --

    def shapegroup(self, node) -> int:
        """The object of a `shapegroup` (its index in the builder), read once: its shapes in the
        group's space."""
        if id(node) not in self.groups:
            obj = self.builder.add_object(node.attrs.get("id", "shapegroup"))
            self.groups[id(node)] = obj
            for child in node.children:
                if child.tag == "shape":
                    if child.attrs.get("type") in ("shapegroup", "instance"):
                        _fail(child, "a shapegroup cannot hold shapegroups or instances (nor can Mitsuba's)")
                    self.shape(child, obj)
        return self.groups[id(node)]

    def instance(self, node, props):
        """An `instance`: the shapegroup it refers to, through its to_world."""
        refs = [c for c in node.children if c.tag in ("ref", "shape")]
        target = self.resolve(refs[0]) if refs and refs[0].tag == "ref" else refs[0] if refs else None
        if target is None or target.tag != "shape" or target.attrs.get("type") != "shapegroup":
            _fail(node, "needs a shapegroup (a <ref> to one)")
        self.builder.add_instance(self.shapegroup(target), self.get(props, "to_world", np.eye(4), ("transform",)),
                                  node.where())

    def shape(self, node, group: int = None):
        """A shape of the scene, or of the shapegroup whose object is `group`."""
        kind = node.attrs.get("type")
        props = self.properties(node)
        if kind == "instance":
            return self.instance(node, props)
        bsdf, emission, media = None, None, {}
        for child in node.children:
            # Mitsuba 3's Shape takes a BSDF by its place, whatever its name (src/render/shape.cpp,
            # the constructor's loop over props.objects()): a <ref name="bsdf"> as its exporters
            # write it, too
            if child.tag == "bsdf" or child.tag == "ref" and ("name" not in child.attrs
                                                              or self.resolve(child).tag == "bsdf"):
                bsdf = child
                if "name" in child.attrs:
                    props.read.add(child.attrs["name"])
            elif child.tag == "emitter":
                if child.attrs.get("type") != "area":
                    warn(f"{child.where()}: a shape's emitter must be area; ignored")
                    continue
                if group is not None:
                    warn(f"{child.where()}: an emitter in a shapegroup; instances have no area lights "
                         "(nor do Mitsuba's), so pathtrace ignores it")
                    continue
                emission = self.color(self.properties(child), "radiance", 1.0)
            elif child.tag in ("medium", "ref") and child.attrs.get("name") in ("interior", "exterior"):
                media[child.attrs["name"]] = self.medium(child)
                props.read.add(child.attrs["name"])
            elif child.tag in ("medium", "sensor"):
                warn(f"{child.where()}: not supported; ignored")
        if emission is not None and bsdf is not None and self.material_node(bsdf).attrs.get("type") == "null":
            _fail(node, "an area emitter on a null BSDF: pathtrace's null surfaces cannot emit")
        material = self.material_row(bsdf, emission)
        # Mitsuba 3: a shape with a medium on either side is a transition, the other side vacuum
        interface = MediumInterface(media.get("interior", -1), media.get("exterior", -1)) if media else None
        m = self.get(props, "to_world", np.eye(4), ("transform",))
        name = node.attrs.get("id")
        if kind in SHAPES:
            values = {p.mitsuba: self.parameter(props, p, p.mitsuba) for p in SHAPES[kind].mitsuba_parameters}
            values = {p.mitsuba: p.mitsuba_default if values[p.mitsuba] is None else values[p.mitsuba]
                      for p in SHAPES[kind].mitsuba_parameters}
            values, local, texture_uv, flip = SHAPES[kind].from_mitsuba(values, m, node.where())
            problem = SHAPES[kind].check(values)
            if problem:
                _fail(node, f"the {kind}'s {problem}")
            shape = Shape(name or f"{kind} {len(self.builder.shapes)}", kind, values, m @ local, material,
                          flip=flip, texture_uv=texture_uv, media=interface)
            if SHAPES[kind].too_flat(shape):
                # Mitsuba 3 would intersect it through a near-singular inverse; the kernels cannot
                # (pathtrace.shapes.shape.MIN_DETERMINANT), and what it covers is next to nothing
                warn(f"{node.where()}: to_world shrinks or flattens the {kind} beyond what the kernels can "
                     f"invert (|det| below {MIN_DETERMINANT:g}); pathtrace leaves it out")
                return
            if np.any(np.abs(np.array(shape.bounds(SHAPES[kind]))) > MAX_COORDINATE):
                _fail(node, f"the {kind} reaches beyond {MAX_COORDINATE:g}, which float32 cannot trace")
            return self.builder.add_to(group, shape)
        normals = None
        if kind in ("rectangle", "cube"):
            vertices, faces, uvs = mitsuba_rectangle() if kind == "rectangle" else mitsuba_cube()
        elif kind in ("obj", "ply"):
            filename = self.get(props, "filename", kinds=("string",))
            if filename is None:
                _fail(node, "needs a filename")
            vertices, faces, normals, uvs = self.mesh_files.read(node.file.parent / filename, node.where())
            if self.get(props, "face_normals", False, ("boolean",)):
                normals = None
            smooth = normals is None and not self.get(props, "face_normals", False, ("boolean",))
            if smooth:                        # Mitsuba 3 smooths a mesh that has no normals
                normals = vertex_normals(vertices, faces)
            origin = MeshFile(str(node.file.parent / filename), m, normals is None,
                              self.get(props, "flip_normals", False, ("boolean",)), smooth)
            name = name or Path(filename).stem
        else:
            warn(f"{node.where()}: pathtrace has no {kind} shape; it ignores this one")
            props.ignore()
            return
        if kind not in ("obj", "ply"):
            vertices, faces, normals, uvs = check_mesh(vertices, faces, None, uvs, node.where())
        vertices, faces, normals, turned = place_mesh(vertices, faces, normals, m, self.get(
            props, "flip_normals", False, ("boolean",)), True, node.where())
        origin = origin if kind in ("obj", "ply") and not turned else None     # turned: written anew
        self.builder.add_to(group, Mesh(name or f"{kind} {len(self.builder.meshes)}", vertices, faces, normals, material,
                                        origin.path if origin else "", origin, uvs, interface))


def read_mitsuba_file(path) -> Scene:
    return _Reader(Path(path)).read()
