"""Mitsuba 3's XML syntax as the Mitsuba reader (app/scene/mitsuba.py) reads it: the element
tree with each element's file and line, <include>s spliced, <default>s and $names substituted,
ids and the <ref>s to them, and each element's properties (Props) and their values (numbers,
colours, points, transforms). Every problem names the file and line, e.g.
    cbox.xml:12: <float name="radius">: 'abc' is not a number

Files come from strangers, so the parser is expat with document type declarations refused (no
entity expansion, no external entities: what defusedxml guards against), and sizes are bounded:
the file, the element count, nesting and include depth."""

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np

from pathtrace.errors import UserError, cut, short, warn, with_article
from pathtrace.scene import transform
from pathtrace.scene.known_names import Unread

MAX_XML_BYTES = 64 << 20
MAX_ELEMENTS = 1_000_000   # in a file and its includes together, as MAX_XML_BYTES
MAX_NESTING = 64           # elements inside elements (a Mitsuba scene needs a handful)
MAX_INCLUDE_DEPTH = 8


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


def fail(node, problem):
    raise UserError(f"{node.where()}: {problem}")


def refuse(props, node, error: ValueError, names: dict = None):
    """A type's ValueError ("<field>: <problem>") as one line naming the property's element
    (`names`: the Mitsuba name of a field of pathtrace's), or the element's where it has none."""
    field, sep, problem = str(error).partition(": ")
    field = (names or {}).get(field, field)
    fail(props.get(field, node) if sep else node, str(error) if not sep else f"{field}: {problem}")


def _float(node, text, what="value"):
    try:
        value = float(text)
    except (TypeError, ValueError):
        fail(node, f"{what} {short(text)} is not a number")
    if not math.isfinite(value) or abs(value) > 3.0e38:
        fail(node, f"{what} {short(text)} is not a finite float32")
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
            fail(node, f"value must be 1 or 3 numbers, got {short(node.attrs['value'])}")
        return np.array(v)
    return np.array([_float(node, node.attrs.get(k, "0"), k) for k in "xyz"])


def _color(node):
    """<rgb value="r, g, b"> or one grey value; <spectrum value="v"> as one value (a spectrum
    of wavelength:value pairs is averaged, with a warning)."""
    text = node.attrs.get("value", "")
    if node.tag == "spectrum" and ":" in text:
        pairs = [p.split(":") for p in re.split(r"[,\s]+", text.strip()) if p]
        if any(len(p) != 2 for p in pairs):
            fail(node, f"a spectrum is wavelength:value pairs, got {short(text)}")
        values = [_float(node, v) for _, v in pairs]
        warn(f"{node.where()}: a sampled spectrum; pathtrace renders RGB and uses its mean, {np.mean(values):.4g}")
        return np.full(3, float(np.mean(values)))
    v = _floats(node, text)
    if len(v) == 1:
        v = v * 3
    if len(v) != 3:
        fail(node, f"value must be 1 or 3 numbers, got {short(text)}")
    if min(v) < 0:
        fail(node, f"a colour must not be negative, got {short(text)}")
    return np.array(v)


def _lookat(node):
    o, t, up = (np.array(_floats(node, node.attrs.get(k, d), k)) for k, d in
                (("origin", ""), ("target", ""), ("up", "0, 1, 0")))
    if len(o) != 3 or len(t) != 3 or len(up) != 3:
        fail(node, "origin, target and up must be 3 numbers each")
    try:
        return transform.look_at(o, t, up)      # x is the image's left in Mitsuba's camera space
    except ValueError as e:
        fail(node, str(e))


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
                fail(op, "scale must be 1 or 3 non-zero numbers")
            step = transform.scaling(s)
        elif op.tag == "rotate":
            axis = _vector(op) if "value" not in op.attrs else np.array(_floats(op, op.attrs["value"]))
            if len(axis) != 3 or not np.linalg.norm(axis) > 1e-30:
                fail(op, "the rotation axis must be 3 numbers, not all (near) zero")
            step = transform.rotation(axis, _float(op, op.attrs.get("angle"), "angle"))
        elif op.tag == "matrix":
            v = _floats(op, op.attrs.get("value", ""))
            if len(v) not in (9, 16):
                fail(op, f"a matrix has 9 or 16 numbers, got {len(v)}")
            step = np.eye(4)
            if len(v) == 9:
                step[:3, :3] = np.reshape(v, (3, 3))
            else:
                step = np.reshape(v, (4, 4))
            if abs(np.linalg.det(step[:3, :3])) < 1e-12 or not np.allclose(step[3], [0, 0, 0, 1]):
                fail(op, "must be an invertible affine transform (last row 0 0 0 1)")
        elif op.tag == "lookat":
            step = _lookat(op)
        else:
            fail(op, "unknown transform operation (translate, rotate, scale, matrix, lookat)")
        m = step @ m
        # the normals' matrix is the inverse transpose: it must exist in float64 and hold in float32
        det = np.linalg.det(m[:3, :3])
        if not (np.all(np.isfinite(m)) and np.abs(m).max() <= 3.0e38 and abs(det) > 1e-36):
            fail(op, "the transform so far is singular or beyond float32 (a scale that underflows?)")
    return m


class XmlScene:
    """A scene file's elements, read once: its <default>s, ids, and each element's Props."""

    def __init__(self, path: Path):
        self.path = path
        self.budget = [MAX_XML_BYTES, MAX_ELEMENTS]   # bytes and elements left (parse_xml)
        self.defaults = {}
        self.named = {}             # id -> Node
        self.props = {}             # id(Node) -> its Props (properties())
        self.version = "3.0.0"      # the <scene>'s (elements())

    def elements(self) -> list:
        """The scene's top-level elements, its includes spliced and its $names substituted."""
        root = parse_xml(self.path, self.budget)
        self.substitute(root)
        self.version = version = root.attrs.get("version", "3.0.0")
        if not version.startswith(("2.", "3.")):
            warn(f"{root.where()}: version {version}; pathtrace reads Mitsuba 3 scenes")
        nodes = self.expand(root)
        self.named = self.declared_ids(nodes)
        self.check_reference_cycles()
        return nodes

    def substitute(self, node):
        for k, v in node.attrs.items():
            if "$" in v:
                def value(m):
                    if m.group(1) not in self.defaults:
                        fail(node, f"${m.group(1)} has no <default> value")
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
                    fail(child, "needs name and value")
                self.defaults.setdefault(name, child.attrs["value"])
                continue
            if child.tag == "include":
                if depth >= MAX_INCLUDE_DEPTH:
                    fail(child, f"includes nest deeper than {MAX_INCLUDE_DEPTH}")
                name = child.attrs.get("filename")
                if not name:
                    fail(child, "needs a filename")
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
                fail(node, f"{short(text)} is not an integer")
        if tag == "boolean":
            if text not in ("true", "false"):
                fail(node, f"must be true or false, got {short(text)}")
            return text == "true"
        if tag == "string":
            if text is None:
                fail(node, "needs a value")
            return text
        if tag in ("rgb", "spectrum"):
            return _color(node)
        if tag in ("point", "vector"):
            return _vector(node)
        if tag == "transform":
            return _transform(node)
        fail(node, "unexpected element here")

    def get(self, props, name, default=None, kinds=None):
        node = props.get(name)
        if node is None:
            return default
        if node.tag == "ref":
            node = self.resolve(node)
        if kinds and node.tag not in kinds:
            fail(node, f"'{name}' must be {with_article(' or '.join(kinds))}")
        return self.value(node)

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
                    fail(ref, f"a reference cycle: {short(' -> '.join(cycle))}")
                if target not in state:
                    state[target] = 1
                    path.append(target)
                    stack.append((target, iter(refs[target])))

    def resolve(self, ref):
        target = self.named.get(ref.attrs.get("id"))
        if target is None:
            fail(ref, f"no element has id {short(ref.attrs.get('id'))}")
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
