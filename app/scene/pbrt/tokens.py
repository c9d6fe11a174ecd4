"""pbrt-v4's scene file syntax: tokens (words, quoted strings, brackets; '#' comments) and
parameter lists ("type name" value). A bracketed list without strings, which is where a large
file's bytes are (inline meshes), is converted by NumPy as one slice of the text, not token by
token, so that 100 MB of numbers read in seconds."""

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pathtrace.errors import UserError, cut

# the whitespace and comments before a token
_SKIP = re.compile(r"(?:\s+|#[^\n]*)*")
_WORD = re.compile(r"[^\s\[\]\"#]+")
FLOAT32_MAX = float(np.finfo(np.float32).max)

# pbrt-v4's parameter types, and the number of values each element takes
PARAM_TYPES = {"integer": 1, "float": 1, "point2": 2, "vector2": 2, "point3": 3, "vector3": 3,
               "normal3": 3, "normal": 3, "rgb": 3, "spectrum": 1, "blackbody": 1, "bool": 1, "string": 1,
               "texture": 1}
# pbrt-v3's names of types, which pbrt-v4 refuses ("unknown parameter type",
# ParameterDictionary::checkParameterTypes, src/pbrt/paramdict.cpp): only its --upgrade renames
# them (src/pbrt/parser.cpp, the parameters' "formatting" branch)
PBRT_V3_TYPES = {"point": "point3", "vector": "vector3", "color": "rgb"}
NUMERIC = {name for name in PARAM_TYPES if name not in ("bool", "string", "texture", "spectrum")}


class Tokens:
    """The tokens of one file, read on demand. Each token is (kind, value, offset): kind "word",
    "string", "[", "]" or "numbers" (a bracketed list of numbers only, as a float64 array)."""

    def __init__(self, text: str, path: Path):
        self.text, self.path, self.pos = text, path, 0
        self._lines = None
        self.peeked = None

    def line(self, offset: int) -> int:
        if self._lines is None:
            self._lines = np.flatnonzero(np.frombuffer(self.text.encode("utf-8", "surrogateescape"), np.uint8) == 10) \
                if self.text.isascii() else np.array([m.start() for m in re.finditer("\n", self.text)])
        return int(np.searchsorted(self._lines, offset)) + 1

    def where(self, offset: int) -> str:
        return f"{self.path}:{self.line(offset)}"

    def fail(self, offset: int, problem: str):
        raise UserError(f"{self.where(offset)}: {problem}")

    def peek(self):
        if self.peeked is None:
            self.peeked = self._next()
        return self.peeked

    def next(self):
        token = self.peek()
        self.peeked = None
        return token

    def _next(self):
        text = self.text
        pos = _SKIP.match(text, self.pos).end()
        if pos >= len(text):
            self.pos = pos
            return ("end", None, pos)
        c = text[pos]
        if c == '"':
            end = text.find('"', pos + 1)
            newline = text.find("\n", pos + 1)
            if end < 0 or 0 <= newline < end:
                self.fail(pos, "an unterminated string")
            self.pos = end + 1
            return ("string", text[pos + 1:end], pos)
        if c == "[":
            end = text.find("]", pos + 1)
            if end >= 0:
                inner = text[pos + 1:end]
                if '"' not in inner and "#" not in inner and "[" not in inner:
                    values = _parse_numbers(inner)
                    if values is not None:
                        self.pos = end + 1
                        return ("numbers", values, pos)
            self.pos = pos + 1
            return ("[", None, pos)
        if c == "]":
            self.pos = pos + 1
            return ("]", None, pos)
        m = _WORD.match(text, pos)
        self.pos = m.end()
        return ("word", m.group(), pos)


def _parse_numbers(inner: str):
    """The numbers of a bracketed list as float64, or None where it holds words (bools).
    Indices, whole numbers only, convert 2.5x faster as integers."""
    words = inner.split()
    if not any(c in inner for c in ".eEnNiI"):
        try:
            return np.array(words, np.int64).astype(np.float64)
        except (ValueError, OverflowError):
            pass
    try:
        return np.array(words, np.float64)
    except ValueError:
        return None


def number(tokens: Tokens, what: str) -> float:
    kind, value, offset = tokens.next()
    if kind == "numbers" and len(value) == 1:
        return float(value[0])
    if kind == "word":
        try:
            return float(value)
        except ValueError:
            pass
    tokens.fail(offset, f"{what}: expected a number, got {describe((kind, value, offset))}")


def numbers(tokens: Tokens, count: int, what: str) -> np.ndarray:
    """`count` numbers, bare or in one bracketed list (pbrt takes both: Transform [ ... ])."""
    kind, value, offset = tokens.peek()
    if kind == "numbers":
        tokens.next()
        if len(value) != count:
            tokens.fail(offset, f"{what} takes {count} numbers, got {len(value)}")
        out = value
    else:
        if kind == "[":
            tokens.next()
        out = np.array([number(tokens, what) for _ in range(count)])
        if kind == "[" and tokens.next()[0] != "]":
            tokens.fail(offset, f"{what} takes {count} numbers in one [ ]")
    if not np.all(np.isfinite(out)) or np.any(np.abs(out) > FLOAT32_MAX):
        tokens.fail(offset, f"{what}: a value beyond what float32 holds")
    return out


def string(tokens: Tokens, what: str) -> str:
    kind, value, offset = tokens.next()
    if kind != "string":
        tokens.fail(offset, f"{what}: expected a quoted string, got {describe((kind, value, offset))}")
    return value


def describe(token) -> str:
    kind, value, _ = token
    return {"end": "the end of the file", "[": "'['", "]": "']'", "numbers": "a list of numbers",
            "string": f'"{cut(str(value))}"'}.get(kind, f"'{cut(str(value))}'")


@dataclass
class Param:
    type: str
    name: str
    values: object            # float64 array for numeric types; a list of str or bool otherwise
    offset: int
    used: bool = False


@dataclass
class ParamList:
    """A directive's parameters, looked up by name and type; each lookup checks the type and
    the number of values and marks the parameter used, so that the reader can warn of the rest."""
    tokens: Tokens
    params: dict = field(default_factory=dict)

    def where(self, name: str) -> str:
        return f"{self.tokens.where(self.params[name].offset)}: '{name}'"

    def fail(self, name: str, problem: str):
        raise UserError(f"{self.where(name)}: {problem}")

    def get(self, name: str, types: tuple, count: int = 1):
        """The parameter `name`'s values if it is of one of `types` (and `count` elements, or
        any number for count 0), else None where it is absent."""
        p = self.params.get(name)
        if p is None:
            return None
        if p.type not in types:
            self.fail(name, f"must be {' or '.join(types)}, got {p.type}")
        p.used = True
        n = len(p.values) // PARAM_TYPES[p.type]
        if count and n != count:
            self.fail(name, f"takes {count} value{'s' if count > 1 else ''}, got {n}")
        return p.values

    def type_of(self, name: str):
        p = self.params.get(name)
        return p.type if p else None

    def float(self, name, default=None):
        if self.type_of(name) == "integer":
            # pbrt-v4's lookups match the type as written (src/pbrt/paramdict.cpp, lookupSingle):
            # an "integer" is never read as a float, and pbrt-v4 refuses it as unused
            self.fail(name, f'pbrt-v4 reads a float here and refuses an integer ("{name}": unused parameter); '
                            f'write "float {name}"')
        v = self.get(name, ("float",))
        return default if v is None else float(v[0])

    def int(self, name, default=None):
        v = self.get(name, ("integer",))
        return default if v is None else int(v[0])

    def bool(self, name, default=None):
        v = self.get(name, ("bool",))
        return default if v is None else v[0]

    def string(self, name, default=None):
        v = self.get(name, ("string", "texture"))
        return default if v is None else v[0]

    def floats(self, name, types=("float",)):
        return self.get(name, types, 0)

    def point(self, name, default=None):
        v = self.get(name, ("point3",))
        return default if v is None else np.asarray(v, np.float64)

    def unused(self) -> list:
        return [p for p in self.params.values() if not p.used]


def parameters(tokens: Tokens) -> ParamList:
    """The "type name" value pairs that follow a directive's own arguments."""
    out = ParamList(tokens)
    while True:
        kind, decl, offset = tokens.peek()
        if kind != "string":
            return out
        tokens.next()
        words = decl.split()
        if len(words) != 2:
            tokens.fail(offset, f'"{cut(decl)}": a parameter is declared as "type name"')
        ptype, name = words
        if ptype in PBRT_V3_TYPES:
            tokens.fail(offset, f'"{cut(decl)}": {ptype} is pbrt-v3\'s parameter type, which pbrt-v4 refuses; '
                                f'write "{PBRT_V3_TYPES[ptype]} {cut(name)}" (as pbrt-v4\'s --upgrade does)')
        if ptype not in PARAM_TYPES:
            tokens.fail(offset, f'"{cut(decl)}": unknown parameter type {cut(ptype)!r} '
                                f"(pbrt-v4 has {', '.join(PARAM_TYPES)})")
        if name in out.params:
            tokens.fail(offset, f"'{cut(name)}' is given twice")
        out.params[name] = Param(ptype, name, _values(tokens, ptype, name, offset), offset)


def _written(tokens: Tokens, start: int, index: int) -> str:
    """The `index`th value of the list at `start` as the file wrote it ("1e20", not the
    -9223372036854775808 of a cast), for a message."""
    text = tokens.text
    end = text.find("]", start) if text[start] == "[" else start + len(_WORD.match(text, start).group())
    words = text[start + (text[start] == "["):end if end >= 0 else len(text)].split()
    return cut(words[index]) if index < len(words) else "?"


def _values(tokens: Tokens, ptype: str, name: str, offset: int):
    kind, value, at = tokens.next()
    start = at
    if kind == "numbers":
        items = value
    elif kind == "[":
        items = []
        while True:
            kind, v, at = tokens.next()
            if kind == "]":
                break
            if kind == "end":
                tokens.fail(offset, f"'{cut(name)}': an unterminated '['")
            if kind not in ("string", "word"):
                tokens.fail(at, f"'{cut(name)}': unexpected {describe((kind, v, at))}")
            items.append((kind, v, at))
    elif kind in ("string", "word"):
        items = [(kind, value, at)]
    else:
        tokens.fail(at, f"'{cut(name)}': expected a value, got {describe((kind, value, at))}")
    if ptype == "spectrum" and not isinstance(items, np.ndarray) and all(k == "word" for k, _, _ in items):
        ptype = "float"           # wavelength-value pairs written bare
    if ptype in NUMERIC or (ptype == "spectrum" and isinstance(items, np.ndarray)):
        if not isinstance(items, np.ndarray):
            if any(k != "word" for k, _, _ in items):
                tokens.fail(offset, f"'{cut(name)}': {ptype} values must be numbers")
            try:
                items = np.array([float(v) for _, v, _ in items], np.float64)
            except ValueError:
                tokens.fail(offset, f"'{cut(name)}': {ptype} values must be numbers")
        per = PARAM_TYPES[ptype]
        if len(items) == 0 or len(items) % per:
            tokens.fail(offset, f"'{cut(name)}': {ptype} takes values in groups of {per}, got {len(items)}")
        biggest = float(np.max(np.abs(items)))       # one reduction: NaN fails the comparison too
        if not biggest <= FLOAT32_MAX:
            bad = int(np.argmax(~(np.abs(items) <= FLOAT32_MAX)))
            tokens.fail(offset, f"'{cut(name)}': {_written(tokens, start, bad)} is not finite, or beyond what float32 holds")
        if ptype == "integer":
            if np.any(items != np.round(items)):
                bad = int(np.argmax(items != np.round(items)))
                tokens.fail(offset, f"'{cut(name)}': integer values must be whole numbers, got {_written(tokens, start, bad)}")
            if biggest >= 2**31:            # pbrt-v4 reads integers as C ints
                bad = int(np.argmax(np.abs(items) >= 2**31))
                tokens.fail(offset, f"'{cut(name)}': integer values must fit in 32 bits, got {_written(tokens, start, bad)}")
        return items
    if isinstance(items, np.ndarray):
        tokens.fail(offset, f"'{cut(name)}': {ptype} values must be quoted strings")
    if ptype == "bool":
        out = []
        for k, v, at in items:
            if v not in ("true", "false"):
                tokens.fail(at, f"'{cut(name)}': a bool is true or false, got {cut(str(v))}")
            out.append(v == "true")
        return out
    if any(k != "string" for k, _, _ in items):
        tokens.fail(offset, f"'{cut(name)}': {ptype} values must be quoted strings")
    return [v for _, v, _ in items]

