"""Reading Wavefront OBJ files with NumPy over the whole file, never a Python loop over its lines.

What is read: `v` (x y z; more values, such as colours, ignored), `vt` (u [v [w]]: v is 0
where missing, as the format has it; w ignored), `vn` and `f` with corners v, v/vt, v//vn or
v/vt/vn (an empty field, as in `1/` or `1/2/`, is taken as absent). Indices count from 1 or,
negative, back from the last element of their kind read so far (the format's rule); an index
beyond what the file has read so far is refused. A polygon becomes a fan of triangles about its
first corner (as trimesh's reader made it, so that a quad keeps its diagonal), and a face of
fewer than three corners is skipped, with a warning (a file cut short ends in one). Comments
(`#`), indented lines, `\\` continuing a line and a UTF-8 byte order mark are taken as the
format and editors have them; other statements (o, g, s, usemtl, mtllib, l, p, vp, ...) are
ignored: the scene's material shades the mesh.

A vertex is each distinct (v, vt, vn) triple that faces use, as trimesh and Mitsuba 3 split
them: the kernels take one normal and uv per vertex. Vertices no face uses are left out, and
the others keep the order of their v lines (a split vertex's copies ordered by their vt and vn
indices), as trimesh's reader gave them. Texture coordinates are kept where every face corner
has one, normals likewise (where some corners lack them, the mesh is shaded as one without).
vt's v comes as OBJ places it, v = 0 at the bottom, and is flipped to Mitsuba's convention
(pathtrace.scene.meshes). A problem is one line naming the file's line: the first in the file."""

import codecs
import re

import numpy as np

from pathtrace.errors import UserError, cut, short

_KINDS = {"v": "a vertex", "vt": "a texture coordinate", "vn": "a normal"}


# bytes are classified by comparisons: a lookup in a table of 256 took 5x as long
def _space(b):
    """A space within a line: bytes.split()'s whitespace less the line end."""
    return (b == 32) | (b == 9) | ((b - 11) <= 2)


def _blank(b):
    """A space or a line end: bytes.split()'s whitespace."""
    return (b == 32) | ((b - 9) <= 4)


def _digit(b):
    return (b - 48) < 10


def parse_obj(data: bytes, where: str, warn=None):
    """(vertices, faces, normals, uvs) of an OBJ file's bytes, normals and uvs None where the
    file has none for some corner; `where` names the file in messages, and `warn` takes the line
    that says how many faces of fewer than three corners were skipped (a file cut short ends in
    one)."""
    lines = _Lines(data)
    problems = []
    tables = {}
    for kind in ("v", "vt", "vn"):
        tables[kind], problem = _table(lines, kind)
        if problem:
            problems.append(problem)
    faces = _Faces(lines)
    if faces.problem:
        problems.append(faces.problem)
    if problems:
        line, message = min(problems, key=lambda p: p[0])
        raise UserError(f"{where}: line {lines.number(line)}: {message}")
    if len(faces.short) and warn is not None:
        warn(f"{where}: line {lines.number(faces.short[0])}: skipped {len(faces.short)} face(s) of fewer than "
             "three corners")
    return faces.mesh(tables["v"], tables["vt"], tables["vn"])


class _Lines:
    """A file's lines: where each starts (after its indentation) and ends, and which hold v,
    vt, vn and f statements."""

    def __init__(self, data: bytes):
        self.data = data
        # a continued line's backslash and line end become spaces, and a byte order mark spaces
        # too, so that every byte keeps its offset: line numbers are counted in `data`
        text = data.replace(b"\\\r\n", b"   ").replace(b"\\\n", b"  ") if b"\\" in data else data
        if text.startswith(codecs.BOM_UTF8):
            text = b"   " + text[3:]
        n = len(text)
        # two bytes past the last line's end, so that a keyword's next two bytes can be read
        self.buf = np.frombuffer(text + b"\n\n\n", np.uint8)
        self.ends = np.flatnonzero(self.buf[:n + 1] == 10)
        s = np.empty_like(self.ends)
        s[0], s[1:] = 0, self.ends[:-1] + 1
        self.starts = s.copy()
        indented = np.flatnonzero(_space(self.buf[s]))
        while len(indented):                     # as many passes as the deepest indentation
            s[indented] += 1
            indented = indented[_space(self.buf[s[indented]])]
        b0, b1, b2 = self.buf[s], self.buf[s + 1], self.buf[s + 2]
        v = b0 == ord("v")
        self.rows = {"v": np.flatnonzero(v & _blank(b1)),
                     "vt": np.flatnonzero(v & (b1 == ord("t")) & _blank(b2)),
                     "vn": np.flatnonzero(v & (b1 == ord("n")) & _blank(b2)),
                     "f": np.flatnonzero((b0 == ord("f")) & _blank(b1))}
        self.first = s                           # the keyword's first byte
        self.last = self.ends                    # where a statement's values end: '\n' or '#'
        self.comments = b"#" in text
        if self.comments:
            hashes = np.flatnonzero(self.buf[:n] == ord("#"))
            self.last = self.ends.copy()
            np.minimum.at(self.last, np.searchsorted(self.ends, hashes), hashes)

    def contents(self, kind: str):
        """The values of `kind`'s lines, each line's followed by a line end (and perhaps more
        blanks), as one array, and the positions of those line ends in it."""
        rows = self.rows[kind]
        if not len(rows):
            return np.zeros(0, np.uint8), np.zeros(0, np.int64)
        first, last = self.first[rows], self.last[rows]
        lo, hi = first[0], last[-1] + 1
        if rows[-1] - rows[0] + 1 == len(rows) and not (self.comments and np.any(last != self.ends[rows])):
            # one block of lines without comments (as files are written): the block with its
            # keywords blanked
            out = self.buf[lo:hi].copy()
            for k in range(len(kind)):
                out[first - lo + k] = ord(" ")
            return out, last - lo
        first = first + len(kind)
        marks = np.zeros(hi - lo + 1, np.int8)
        marks[first - lo] += 1
        marks[last + 1 - lo] -= 1
        out = self.buf[lo:hi][np.cumsum(marks[:-1], dtype=np.int8).view(bool)]
        ends = np.cumsum(last - first + 1) - 1
        out[ends] = 10
        return out, ends

    def so_far(self, kind: str, rows: np.ndarray):
        """How many `kind` statements precede each of `rows`: one number where all precede them."""
        mine = self.rows[kind]
        if not len(mine) or not len(rows) or mine[-1] < rows[0]:
            return len(mine)
        return np.searchsorted(mine, rows)

    def number(self, row: int) -> int:
        """The line number (from 1) in the file of line `row`."""
        return self.data.count(b"\n", 0, int(self.starts[row])) + 1


def _tokens(text: np.ndarray):
    """Where the tokens (runs of bytes between blanks) of `text` start, and where they stop (the
    blank after each)."""
    blank = _blank(text)
    edge = np.empty(len(text) + 1, bool)      # a token starts or stops before each byte
    edge[0], edge[-1] = len(text) and not blank[0], False
    np.not_equal(blank[1:], blank[:-1], out=edge[1:-1])
    edges = np.flatnonzero(edge)
    return edges[0::2], edges[1::2]


_POWERS = 10.0 ** np.arange(16)


def _decimals(text: np.ndarray, starts: np.ndarray, stops: np.ndarray):
    """The values of the tokens of `text` where each is a decimal in fixed point of at most 15
    characters with one point, as exporters write them ("-0.250000"), or None: as integers by
    NumPy's reader (digits and a leading sign only, which it reads whole), each divided by its
    power of ten, which rounds as float() does (both exact: at most 15 digits, 10^k for k <=
    15); 2x faster than float() of each for large files."""
    raw = text.tobytes()
    if raw.translate(None, b"0123456789.-+ \t\n\r\v\f") or (stops - starts).max() > 15:
        return None
    dots = np.flatnonzero(text == ord("."))
    if len(dots) != len(starts) or np.any(dots < starts) or np.any(dots >= stops):
        return None                              # a token without a point, or with two
    signs = np.flatnonzero((text == ord("-")) | (text == ord("+")))
    signed = (text[starts] == ord("-")) | (text[starts] == ord("+"))
    if len(signs) != np.count_nonzero(signed) or np.any(stops - starts - signed < 2):
        return None                              # a sign within a token, or no digit
    places = stops - dots - 1
    return np.fromstring(raw.replace(b".", b""), np.int64, sep=" ") / _POWERS[places]


def _counts(positions: np.ndarray, ends: np.ndarray, each: int) -> np.ndarray:
    """How many of `positions` (in order) lie in each span that ends at (or before) `ends`: at
    once where each has `each` (a file's lines their statement's count of values, faces three
    corners), else by a search."""
    n = len(ends)
    if len(positions) == each * n and (each == 0 or np.all(positions[each - 1::each] <= ends)
                                       and np.all(positions[each::each] > ends[:-1])):
        return np.full(n, each)
    return np.diff(np.searchsorted(positions, ends, side="right"), prepend=0)


def _table(lines: _Lines, kind: str):
    """The values of the file's `kind` (v, vt or vn) statements as rows of 3 (vt: 2), and the
    first problem in them as (row of the file, message), or None."""
    width = 2 if kind == "vt" else 3
    text, ends = lines.contents(kind)
    rows = lines.rows[kind]
    starts, stops = _tokens(text)
    counts = _counts(starts, ends, width)
    values = _decimals(text, starts, stops) if len(starts) else np.zeros(0)
    problems = []
    if values is None:
        tokens = text.tobytes().split()
        try:
            values = np.array(tokens, np.float64)
        except ValueError:
            bad = next(k for k, token in enumerate(tokens) if not _is_number(token))
            row = int(np.searchsorted(np.cumsum(counts), bad, side="right"))
            problems.append((rows[row], f"{short(tokens[bad].decode('utf-8', 'replace'))} is not a number"))
    need = 1 if kind == "vt" else 3
    short_rows = np.flatnonzero(counts < need)
    if len(short_rows):
        k = short_rows[0]
        what = "u and optionally v" if kind == "vt" else "three coordinates"
        problems.append((rows[k], f"{_KINDS[kind]} ({kind}) needs {what}, got {counts[k]} value(s)"))
    if problems:
        return None, min(problems, key=lambda p: p[0])
    if len(values) == len(counts) * width and np.all(counts == width):
        return values.reshape(-1, width), None
    offsets = np.cumsum(counts) - counts
    table = values[offsets[:, None] + np.arange(need)]
    if kind == "vt":             # v is 0 where a vt has only u
        second = np.where(counts > 1, values[np.minimum(offsets + 1, len(values) - 1)], 0.0)
        table = np.column_stack([table[:, 0], second])
    return table, None


def _is_number(token: bytes) -> bool:
    try:
        np.array([token], np.float64)
    except ValueError:
        return False
    return True


class _Faces:
    """The corners of a file's f statements, checked: each corner's v, vt and vn index (0-based,
    negative ones resolved) and whether it has a vt and a vn (True: all have one), and the
    triangles of corners; or the first problem, (row of the file, message)."""

    def __init__(self, lines: _Lines):
        self.problem, self.short = None, ()
        text, ends = lines.contents("f")
        rows = lines.rows["f"]
        corners, stops = _tokens(text)
        # a corner is v[/[vt][/[vn]]], each index digits after an optional sign
        slash = text == ord("/")
        slashes = np.flatnonzero(slash)
        per = _counts(slashes, stops - 1, len(slashes) // max(len(corners), 1))      # slashes of each corner
        odd = np.flatnonzero(~(_blank(text) | slash | _digit(text)))
        malformed = slash[corners] | (per > 2)
        if len(odd):
            before = text[odd - 1]
            bad = odd[((text[odd] != ord("-")) & (text[odd] != ord("+"))) | ~(_blank(before) | (before == ord("/")))
                      | ~_digit(text[odd + 1])]
            malformed[np.searchsorted(corners, bad, side="right") - 1] = True
        given = text
        if malformed.any():
            # a malformed corner read as vertex 1, so that the corners before it are checked too
            text = text.copy()
            for k in np.flatnonzero(malformed):
                text[corners[k]:stops[k]] = ord(" ")
                text[corners[k]] = ord("1")
            slash = text == ord("/")
            per[malformed] = 0
        raw = text.tobytes()
        # digits and signs only, as checked above, which NumPy's reader takes whole (it reads
        # text of blanks alone as one 0)
        values = np.fromstring(raw.replace(b"/", b" "), np.int64, sep=" ") if len(corners) else np.zeros(0, np.int64)
        self.index, self.has = self.fields(text, slash, per, values, raw.count(b"//"), len(corners))
        problem = malformed.astype(np.int8)      # each corner's first problem: 1 malformed, 2 v, 3 vt, 4 vn
        count = _counts(corners, ends, 3)                 # each face's corners
        line = None                                       # each corner's face, where needed
        so_far = {}
        for code, kind in ((4, "vn"), (3, "vt"), (2, "v")):
            so_far[kind] = lines.so_far(kind, rows)
            if not np.isscalar(so_far[kind]):
                line = np.repeat(np.arange(len(rows)), count) if line is None else line
                so_far[kind] = so_far[kind][line]
            index = self.index[kind]
            resolved = np.where(index > 0, index - 1, index + so_far[kind])
            self.index[kind] = resolved
            outside = (resolved < 0) | (resolved >= so_far[kind])
            if self.has[kind] is not True:
                outside &= self.has[kind]
            problem[outside & ~malformed] = code
        if problem.any():
            k = int(np.argmax(problem != 0))
            corner = given[corners[k]:stops[k]].tobytes().decode("utf-8", "replace")
            if problem[k] == 1:
                message = (f"face corner {short(corner)} is not v, v/vt, v//vn or v/vt/vn indices"
                           if re.fullmatch(r"[+-]?[0-9]+", corner.split("/")[0])
                           else f"face corner {short(corner)} is not a vertex index")
            else:
                kind = ("v", "vt", "vn")[problem[k] - 2]
                count = np.broadcast_to(so_far[kind], len(corners))[k]
                what = (f"{cut(corner.split('/')[0])} names a vertex" if kind == "v"
                        else f"{short(corner)} names {_KINDS[kind]} ({kind})")
                message = f"face corner {what} the file does not have ({count} so far; OBJ counts from 1)"
            self.problem = (rows[np.searchsorted(ends, corners[k])], message)
            return
        self.short = rows[count < 3]             # the lines of the faces skipped
        # each face a fan of triangles about its first corner
        if np.all(count == 3):
            self.triangles = None                # the corners, three by three
        else:
            fans = np.maximum(count - 2, 0)
            face = np.repeat(np.arange(len(rows)), fans)
            first = (np.cumsum(count) - count)[face]
            step = np.arange(len(face)) - np.repeat(np.cumsum(fans) - fans, fans) + 1
            self.triangles = np.stack([first, first + step, first + step + 1], 1)

    @staticmethod
    def fields(text, slash, per, values, doubles: int, n: int):
        """Each corner's v, vt and vn index as written (0 where it has none) and whether it has
        a vt and a vn (True where all have one, False where none has), from the slashes of each
        corner and the indices read in order."""
        s = int(per[0]) if n else 0
        if np.all(per == s) and (s < 2 or doubles in (0, n)):
            # every corner of one form: v, v/vt, v//vn or v/vt/vn (if each has all its indices)
            form = {0: ("v",), 1: ("v", "vt"), 2: ("v", "vn") if doubles else ("v", "vt", "vn")}[s]
            if len(values) == len(form) * n:
                columns = values.reshape(-1, len(form))
                index = {kind: columns[:, form.index(kind)] if kind in form else np.zeros(n, np.int64)
                         for kind in ("v", "vt", "vn")}
                return index, {"vt": "vt" in form, "vn": "vn" in form, "v": True}
        # mixed forms: each index's field is 0 at its corner's start, else the slashes since
        separator = _blank(text) | slash
        starts = ~separator
        starts[1:] &= separator[:-1]
        numbers = np.flatnonzero(starts)
        gap = np.where(text[numbers - 1] == ord("/"), 1 + (text[numbers - 2] == ord("/")), 0)
        first = gap == 0
        owner = np.cumsum(first) - 1
        field = np.cumsum(gap)
        field -= field[first][owner]
        index, has = {}, {}
        for f, kind in enumerate(("v", "vt", "vn")):
            at = field == f
            index[kind] = np.zeros(n, np.int64)
            index[kind][owner[at]] = values[at]
            has[kind] = np.zeros(n, bool)
            has[kind][owner[at]] = True
        has["v"] = True
        return index, has

    def mesh(self, v, vt, vn):
        """(vertices, faces, normals, uvs): a vertex per distinct (v, vt, vn) the triangles use."""
        t = slice(None) if self.triangles is None else self.triangles.reshape(-1)
        corner = {"v": self.index["v"][t]}
        for kind in ("vt", "vn"):
            has = self.has[kind]
            if has is True or has is not False and len(corner["v"]) and has[t].all():
                corner[kind] = self.index[kind][t]
        if all(np.array_equal(c, corner["v"]) for c in corner.values()):
            # each v with one vt and one vn: v's vertices that the faces use, in their order
            used = np.zeros(len(v), bool)
            used[corner["v"]] = True
            pick = dict.fromkeys(corner, np.flatnonzero(used))
            inverse = np.cumsum(used)[corner["v"]] - 1
        else:
            key = corner["v"]
            for kind, table in (("vt", vt), ("vn", vn)):
                if kind in corner:
                    if int(key.max()) >= (1 << 62) // len(table):      # keys kept within int64
                        key = np.unique(key, return_inverse=True)[1]
                    key = key * len(table) + corner[kind]
            _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
            pick = {kind: c[first] for kind, c in corner.items()}
        tables = {"v": v, "vt": vt, "vn": vn}
        out = {kind: tables[kind][p] for kind, p in pick.items()}
        uvs = out.get("vt")
        if uvs is not None:
            uvs[:, 1] = 1.0 - uvs[:, 1]
        return out["v"], inverse.reshape(-1, 3), out.get("vn"), uvs
