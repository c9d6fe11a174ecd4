"""pathtrace's TOML format's values, as the TOML reader (app/scene/toml_reader.py) reads them:
tables and their keys, numbers, colours, vectors, names, transforms, uv transforms and inline
meshes, each checked where it is read, every problem one line naming the file and the field, e.g.
    scenes/room.toml: spheres[3].radius: must be positive, got -1
and a scene given as Python's dicts (the API's) made the values tomllib would have given."""

import math

import numpy as np

from pathtrace.errors import UserError, did_you_mean, short
from pathtrace.scene import transform
from pathtrace.scene.meshes import triangulate

MAX_INLINE = 100_000    # vertices or faces written in a scene file; larger meshes belong in files
FLOAT32_MAX = float(np.finfo(np.float32).max)


class TomlValues:
    """A scene file's values, checked, its messages naming it by `label`."""

    def __init__(self, label: str):
        self.label = label

    def fail(self, where, problem):
        raise UserError(f"{self.label}: {where}: {problem}")

    def not_one_of(self, where, value, choices, quoted=False, also=""):
        """Fails at `where`, whose `value` is none of the names `choices`: one line listing them
        (quoted where `quoted`, then `also`), what was given, and the name closest to it."""
        names = [repr(c) if quoted else c for c in choices]
        listed = " or ".join(names) if len(names) == 2 else "one of " + ", ".join(names)
        hint = did_you_mean(value, choices, quoted) if isinstance(value, str) else ""
        self.fail(where, f"must be {listed}{also}, got {short(value)}{hint}")

    def refuse(self, where, error: ValueError):
        """A type's ValueError ("<field>: <problem>", or a problem of the whole) naming the field."""
        field, sep, problem = str(error).partition(": ")
        self.fail(f"{where}.{field}", problem) if sep else self.fail(where, str(error))

    def table(self, data, where, allowed):
        if not isinstance(data, dict):
            self.fail(where, f"must be a table, got {type(data).__name__}")
        unknown = sorted(set(data) - set(allowed))
        if unknown:
            self.fail(where, f"unknown key '{unknown[0]}'{did_you_mean(unknown[0], allowed, quoted=True)} "
                             f"(allowed: {', '.join(sorted(allowed))})")
        return data

    def named_tables(self, data, key) -> dict:
        """The top-level table `key` ([textures], [media], ...): a table of tables by name."""
        tables = data.get(key, {})
        return self.table(tables, key, set(tables) if isinstance(tables, dict) else set())

    def array(self, data, key) -> list:
        """The top-level array of tables `key` ([[lights]], ...)."""
        value = data.get(key, [])
        if not isinstance(value, list):
            self.fail(key, f"must be an array of tables ([[{key}]]), got {type(value).__name__}")
        return value

    def kind_of(self, data, where, kinds, key="type", default=None) -> str:
        """The name among `kinds` that a table entry gives by `key` (`default` where it gives none)."""
        if not isinstance(data, dict):
            self.fail(where, f"must be a table, got {short(data)}")
        kind = data.get(key, default)
        if kind is None:
            self.fail(where, f"missing '{key}' (one of {', '.join(kinds)})")
        if not isinstance(kind, str) or kind not in kinds:
            self.not_one_of(f"{where}.{key}", kind, kinds)
        return kind

    def boolean(self, data, key, where, default):
        value = data.get(key, default)
        if not isinstance(value, bool):
            self.fail(f"{where}.{key}", f"must be true or false, got {short(value)}")
        return value

    def number(self, data, key, where, default=None, low=None, high=None, integer=False):
        if key not in data:
            if default is None:
                self.fail(where, f"missing '{key}'")
            return default
        value = data[key]
        kinds = (int,) if integer else (int, float)
        if isinstance(value, bool) or not isinstance(value, kinds):
            self.fail(f"{where}.{key}", f"must be {'an integer' if integer else 'a number'}, got {short(value)}")
        if integer and not -2**31 <= value < 2**31:
            self.fail(f"{where}.{key}", f"must fit in 32 bits, got {short(value)}")
        if not _is_finite_number(value):
            self.fail(f"{where}.{key}", f"must be finite and within float32's range (3.4e38), got {short(value)}")
        if low is not None and value < low:
            self.fail(f"{where}.{key}", f"must be at least {low}, got {value}")
        if high is not None and value > high:
            self.fail(f"{where}.{key}", f"must be at most {high}, got {value}")
        return value

    def color(self, data, key, where, default=None, high=None):
        """A colour is a number (grey) or a list of three numbers, finite and non-negative."""
        if key not in data:
            if default is None:
                self.fail(where, f"missing '{key}'")
            return np.asarray(default, np.float64)
        value = data[key]
        items = [value] * 3 if isinstance(value, (int, float)) and not isinstance(value, bool) else value
        if not isinstance(items, list) or len(items) != 3:
            self.fail(f"{where}.{key}", f"must be a number or a list of 3 numbers, got {short(value)}")
        for c in items:
            if not _is_finite_number(c):
                self.fail(f"{where}.{key}", f"must hold finite numbers within float32's range, got {short(value)}")
            if c < 0 or (high is not None and c > high):
                bound = f"in [0, {high}]" if high is not None else "non-negative"
                self.fail(f"{where}.{key}", f"must be {bound}, got {short(value)}")
        return np.asarray(items, np.float64)

    def uv_transform(self, data, where) -> np.ndarray:
        """uv_matrix (3 rows of 3, acting on (u, v, 1)), or uv' = uv_offset + R(uv_rotate) (uv_scale
        uv), R turning counter-clockwise by degrees."""
        if "uv_matrix" in data:
            m = data["uv_matrix"]
            if not (isinstance(m, list) and len(m) == 3 and all(
                    isinstance(r, list) and len(r) == 3 and all(_is_finite_number(x) for x in r) for r in m)):
                self.fail(f"{where}.uv_matrix", f"must be 3 rows of 3 finite numbers, got {short(m)}")
            if any(k in data for k in ("uv_scale", "uv_offset", "uv_rotate")):
                self.fail(where, "give either uv_matrix or uv_scale, uv_offset and uv_rotate, not both")
            return np.asarray(m, np.float64)
        scale = self.pair(data, "uv_scale", where, (1.0, 1.0))
        offset = self.pair(data, "uv_offset", where, (0.0, 0.0))
        angle = math.radians(self.number(data, "uv_rotate", where, default=0.0))
        c, s = math.cos(angle), math.sin(angle)
        return np.array([[c * scale[0], -s * scale[1], offset[0]], [s * scale[0], c * scale[1], offset[1]], [0, 0, 1]])

    def pair(self, data, key, where, default):
        value = data.get(key, default)
        items = [value, value] if _is_finite_number(value) else value
        if not (isinstance(items, (list, tuple)) and len(items) == 2 and all(_is_finite_number(x) for x in items)):
            self.fail(f"{where}.{key}", f"must be a number or a list of 2 finite numbers, got {short(value)}")
        return [float(x) for x in items]

    def vector(self, data, key, where, default=None):
        if key not in data:
            if default is None:
                self.fail(where, f"missing '{key}'")
            return np.asarray(default, np.float64)
        value = data[key]
        if not isinstance(value, list) or len(value) != 3 or not all(_is_finite_number(c) for c in value):
            self.fail(f"{where}.{key}", f"must be a list of 3 finite numbers within float32's range, "
                                        f"got {short(value)}")
        return np.asarray(value, np.float64)

    def name(self, data, where, default):
        name = data.get("name", default)
        if not isinstance(name, str) or not name or len(name) > 200:
            self.fail(f"{where}.name", f"must be a non-empty string of at most 200 characters, got {short(name)}")
        return name

    def transform(self, data, where) -> np.ndarray:
        """scale, then rotate, then translate; or a full 4x4 matrix (row-major)."""
        if "matrix" in data:
            if any(k in data for k in ("translate", "rotate", "scale")):
                self.fail(where, "give either 'matrix' or translate/rotate/scale, not both")
            m = data["matrix"]
            if (not isinstance(m, list) or len(m) != 4
                    or not all(isinstance(r, list) and len(r) == 4 and all(_is_finite_number(x) for x in r) for r in m)):
                self.fail(f"{where}.matrix", "must be 4 rows of 4 finite numbers")
            m = np.asarray(m, np.float64)
            if abs(np.linalg.det(m[:3, :3])) < 1e-12 or not np.allclose(m[3], [0, 0, 0, 1]):
                self.fail(f"{where}.matrix", "must be an invertible affine transform (last row 0 0 0 1)")
            return m
        m = np.eye(4)
        if "scale" in data:
            s = data["scale"]
            s = [s] * 3 if _is_finite_number(s) else s
            if not isinstance(s, list) or len(s) != 3 or not all(_is_finite_number(x) and x != 0 for x in s):
                self.fail(f"{where}.scale", f"must be a non-zero number or 3 of them, got {short(data['scale'])}")
            m = transform.scaling(s) @ m
        if "rotate" in data:
            r = data["rotate"]
            if (not isinstance(r, list) or len(r) != 4 or not all(_is_finite_number(x) for x in r)
                    or not any(r[:3])):
                self.fail(f"{where}.rotate", f"must be [axis_x, axis_y, axis_z, degrees] with a non-zero axis, got {short(r)}")
            m = transform.rotation(r[:3], r[3]) @ m
        if "translate" in data:
            m = transform.translation(self.vector(data, "translate", where)) @ m
        return m

    def inline_geometry(self, data, where):
        vertices, faces = data.get("vertices"), data.get("faces")
        if (not isinstance(vertices, list) or not vertices or len(vertices) > MAX_INLINE
                or not all(isinstance(v, list) and len(v) == 3 and all(_is_finite_number(x) for x in v)
                           for v in vertices)):
            self.fail(f"{where}.vertices", f"must be a list of up to {MAX_INLINE} points of 3 finite numbers")
        if (not isinstance(faces, list) or not faces or len(faces) > MAX_INLINE
                or not all(isinstance(f, list) and 3 <= len(f) <= 64
                           and all(isinstance(i, int) and not isinstance(i, bool) for i in f) for f in faces)):
            self.fail(f"{where}.faces", "must be a list of polygons, each 3 to 64 integer vertex indices")
        if any(not 0 <= i < len(vertices) for f in faces for i in f):
            self.fail(f"{where}.faces", f"vertex indices must lie in 0..{len(vertices) - 1}")
        uvs = data.get("uvs")
        if uvs is not None and (not isinstance(uvs, list) or len(uvs) != len(vertices) or not all(
                isinstance(t, list) and len(t) == 2 and all(_is_finite_number(x) for x in t) for t in uvs)):
            self.fail(f"{where}.uvs", f"must be a list of {len(vertices)} pairs of finite numbers, one per vertex")
        return np.asarray(vertices, np.float64), triangulate(faces), None if uvs is None else np.asarray(uvs, np.float64)


def _is_finite_number(x):
    """A number the kernels can hold: an int or float, not a bool, finite as a float32."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return False
    try:
        return math.isfinite(x) and abs(float(x)) <= FLOAT32_MAX
    except OverflowError:       # an integer beyond float64's range
        return False


def as_toml(value):
    """What tomllib would have given for the same data: lists for tuples and arrays, Python
    numbers for NumPy's."""
    if isinstance(value, dict):
        return {k: as_toml(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [as_toml(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value
