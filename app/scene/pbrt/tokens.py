"""pbrt-v4's scene file syntax: tokens (words, quoted strings, brackets; '#' comments) and
parameter lists ("type name" value), and their values: numbers, strings, points and colours
(spectra made rgb: app/scene/spectra.py). The text is cut into tokens by one regular expression pass,
and the bracketed lists of numbers, which is where a large file's bytes are (inline meshes), are
converted by NumPy in bulk, so that reading costs time in proportion to the file's size: 100 MB of
numbers, or 100,000 small directives, read in seconds."""

import re
import warnings
from bisect import bisect_left
from dataclasses import dataclass, field
from itertools import chain
from pathlib import Path

import numpy as np

from pathtrace.errors import UserError, cut, warn
from pathtrace.scene.spectra import blackbody_rgb, emission_rgb, named_spectrum, reflectance_rgb, sampled

# one token, its kind the name of the group it matches: a comment (matched so that its words are
# skipped), a quoted string (its text the group), a quote that the line ends before closing, a
# bracketed list holding no string, comment or bracket (a list of numbers, or of bare words), a
# bracket (its kind the bracket itself), or a word
_TOKEN = re.compile(r'(?P<comment>#[^\n]*)|"(?P<string>[^"\n]*)"|(?P<unterminated>")|(?P<list>\[[^\]"#\[]*\])'
                    r'|(?P<bracket>[\[\]])|(?P<word>[^\s\[\]"#]+)')
_WORD = re.compile(r"[^\s\[\]\"#]+")
FLOAT32_MAX = float(np.finfo(np.float32).max)
# lists longer than this (in characters) are converted one by one, where indices, whole numbers
# only, convert 2.5x faster as integers; the shorter ones together, in one call
_BULK_CHARS = 4096

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
    """The tokens of one file, each (kind, value, offset): kind "word", "string", "[", "]",
    "numbers" (a bracketed list of numbers only, as a float64 array) or "end"."""

    def __init__(self, text: str, path: Path):
        self.text, self.path, self.name = text, path, str(path)
        self._lines = None
        self.checked = {}
        self.tokens = _scan(text, path, self.checked)
        self.index = 0

    def line(self, offset: int) -> int:
        if self._lines is None:
            self._lines = np.flatnonzero(np.frombuffer(self.text.encode("ascii"), np.uint8) == 10).tolist() \
                if self.text.isascii() else [m.start() for m in re.finditer("\n", self.text)]
        return bisect_left(self._lines, offset) + 1

    def where(self, offset: int) -> str:
        return f"{self.name}:{self.line(offset)}"

    def fail(self, offset: int, problem: str):
        raise UserError(f"{self.where(offset)}: {problem}")

    def peek(self):
        return self.tokens[self.index]

    def next(self):
        token = self.tokens[self.index]
        if token[0] != "end":
            self.index += 1
        return token


def _scan(text: str, path: Path, checked: dict):
    """The tokens of `text` (the file at `path`), and in `checked`, for the lists converted in
    bulk, by offset, whether their values are all finite and within float32's range, and whether
    they are all whole numbers that fit in 32 bits (pbrt-v4's integers), which _values would
    otherwise find list by list."""
    # one comprehension, not a loop over the matches: 100,000 small directives are 900,000 tokens
    tokens = [(kind if (kind := m.lastgroup) != "bracket" else m[0], m[m.lastindex], m.start())
              for m in _TOKEN.finditer(text)]
    if "#" in text:
        tokens = [t for t in tokens if t[0] != "comment"]
    if '"' in text:
        for kind, _, at in tokens:
            if kind == "unterminated":
                raise UserError(f"{path}:{text.count(chr(10), 0, at) + 1}: an unterminated string")
    lists = [i for i, t in enumerate(tokens) if t[0] == "list"]
    bulk = [i for i in lists if len(tokens[i][1]) <= _BULK_CHARS]
    if _convert_in_bulk(tokens, bulk, checked) < len(lists):
        tokens = list(chain.from_iterable(_list_tokens(*t) if t[0] == "list" else (t,) for t in tokens))
    tokens.append(("end", None, len(text)))
    return tokens


def _convert_in_bulk(tokens: list, bulk: list, checked: dict) -> int:
    """Replaces the short lists at `bulk` (indices into tokens) by "numbers" tokens, converted by
    one call, their checks in `checked`; returns how many. Where one holds anything but numbers
    (a bool, a typo), they are all left to _list_tokens."""
    inners = [tokens[i][1][1:-1] for i in bulk]
    joined = " " + " ".join(inners)
    if not bulk or not joined.isascii():
        return 0
    # each list's words, counted where a non-space follows a space; a list's part of `joined`
    # is the space before it and its text, so that an empty list has a part too
    b = np.frombuffer(joined.encode("ascii"), np.uint8)
    space = (b == 32) | ((b >= 9) & (b <= 13))
    first = ~space
    first[1:] &= space[:-1]
    bounds = np.concatenate([[0], np.cumsum(first)[np.cumsum([len(x) + 1 for x in inners]) - 1]])
    with warnings.catch_warnings():
        # NumPy warns where it stops at a word that is not a number (and will raise)
        warnings.simplefilter("error")
        try:
            values = np.fromstring(joined, sep=" ")
        except (ValueError, DeprecationWarning):
            return 0
    if len(values) != bounds[-1]:           # a word read as two numbers ("1-2"), or none
        return 0
    in_range = np.abs(values) <= FLOAT32_MAX       # NaN fails the comparison too
    whole = in_range & (values == np.round(values)) & (np.abs(values) < 2**31)
    bad, fraction = (np.diff(np.concatenate([[0], np.cumsum(~flag)])[bounds]) > 0 for flag in (in_range, whole))
    for i, start, end, out, inexact in zip(bulk, bounds[:-1].tolist(), bounds[1:].tolist(), bad.tolist(),
                                           fraction.tolist()):
        at = tokens[i][2]
        tokens[i] = ("numbers", values[start:end], at)
        checked[at] = not out, not inexact
    return len(bulk)


def _list_tokens(kind, value, at):
    """A bracketed list not converted in bulk: one "numbers" token, or where it holds words, its
    brackets and words."""
    values = _parse_numbers(value[1:-1])
    if values is not None:
        return (("numbers", values, at),)
    return (("[", None, at), *(("word", m[0], at + m.start()) for m in _WORD.finditer(value, 1, len(value) - 1)),
            ("]", None, at + len(value) - 1))


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

    def spectrum(self, name, default=None, kind="reflectance"):
        """A colour as rgb: rgb, blackbody, a named spectrum, (wavelength, value) pairs or a float;
        `kind` "reflectance", "illuminant" (luminance 1, as pbrt-v4 normalises a light's spectrum)
        or "unbounded" (an IOR: the mean); the default where absent (None, or a grey or rgb)."""
        ptype = self.type_of(name)
        if ptype is None:
            return None if default is None else np.broadcast_to(np.asarray(default, np.float64), 3).copy()
        if ptype == "rgb":
            return np.asarray(self.get(name, (ptype,)), np.float64)
        if ptype == "float":
            return np.full(3, self.float(name))
        if ptype == "blackbody":
            kelvin = float(self.get(name, ("blackbody",))[0])
            if kelvin <= 0:
                self.fail(name, f"a blackbody's temperature must be positive, got {kelvin:g}")
            try:
                return blackbody_rgb(kelvin)
            except ValueError as e:
                self.fail(name, f"a blackbody of {kelvin:g} K {e}")
        if ptype == "spectrum":
            values = self.get(name, ("spectrum",), 0)
            if isinstance(values, list):
                if len(values) != 1:
                    self.fail(name, "a named spectrum is one quoted name")
                try:
                    rgb, note = named_spectrum(values[0])
                except KeyError:
                    self.fail(name, f"unknown named spectrum {values[0]!r}")
                if note:
                    warn(f"{self.where(name)}: {values[0]} is taken as {note}")
                return rgb
            if len(values) % 2:
                self.fail(name, "a spectrum is (wavelength, value) pairs")
            try:
                curve = sampled(values)
            except ValueError as e:
                self.fail(name, str(e))
            if kind == "illuminant":
                try:
                    return emission_rgb(curve)
                except ValueError as e:
                    self.fail(name, f"the spectrum {e}")
            return reflectance_rgb(curve) if kind == "reflectance" else np.full(3, float(np.mean(curve)))
        self.fail(name, f"must be a colour (rgb, spectrum, blackbody, float), got {ptype}")

    def unused(self) -> list:
        return [p for p in self.params.values() if not p.used]

    def ignore(self):
        """A directive left out or replaced whole, with a warning of its own: its parameters get
        no warnings more."""
        for p in self.params.values():
            p.used = True


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
                # a list of strings holds no numbers and no list: its ']' is missing (the file
                # went on to the next directive), which is told where the list began
                tokens.fail(start, f"'{cut(name)}': its '[' is not closed by a ']' before "
                                   f"{describe((kind, v, at))} at line {tokens.line(at)}")
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
        in_range, whole = tokens.checked.get(start, (None, None))
        if in_range is None:
            in_range = float(np.max(np.abs(items))) <= FLOAT32_MAX     # one reduction: NaN fails it too
        if not in_range:
            bad = int(np.argmax(~(np.abs(items) <= FLOAT32_MAX)))
            tokens.fail(offset, f"'{cut(name)}': {_written(tokens, start, bad)} is not finite, or beyond what float32 holds")
        if ptype == "integer" and not whole:
            if np.any(items != np.round(items)):
                bad = int(np.argmax(items != np.round(items)))
                tokens.fail(offset, f"'{cut(name)}': integer values must be whole numbers, got {_written(tokens, start, bad)}")
            if np.max(np.abs(items)) >= 2**31:            # pbrt-v4 reads integers as C ints
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

