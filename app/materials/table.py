"""A scene's materials: the packed MATERIAL rows the kernels read, with named entries and
per-row access to the parameters (the viewer's editor)."""

from dataclasses import dataclass, field

import numpy as np

from pathtrace.errors import UserError, short
from pathtrace.materials.bsdf import TWOSIDED
from pathtrace.materials.registry import BSDFS, TAGS
from pathtrace.types import MATERIAL


@dataclass
class Material:
    """One material as a scene file states it."""
    type: str
    params: dict = field(default_factory=dict)
    emission: np.ndarray = field(default_factory=lambda: np.zeros(3))
    twosided: bool = False


def pack(type_name: str, params: dict, emission=(0, 0, 0), twosided=False) -> np.ndarray:
    """Rows of MATERIAL for one type. Each parameter and the emission hold one value for all
    rows or one per row: a colour is a number, 3 numbers or an (N, 3) array, a number a scalar
    or an (N,) array. Parameters left out take their defaults; named choices must have been
    resolved (BSDFType.resolve)."""
    bsdf = BSDFS[type_name]
    values = {p.name: _as_rows(params.get(p.name, p.default), p.kind)
              for p in bsdf.params if p.kind != "name"}
    emission = _as_rows(emission, "color")
    lengths = [len(v) for v in values.values()] + [len(emission)]
    n = 0 if 0 in lengths else max(lengths)
    values = {k: np.broadcast_to(v, (n,) + v.shape[1:]) for k, v in values.items()}
    rows = np.zeros(n, MATERIAL)
    bsdf.pack(values, rows)
    rows["emission"][:, :3] = emission
    rows["type"] = TAGS[type_name]
    rows["flags"] = bsdf.flags | (TWOSIDED if twosided else 0)
    rows["continuation"] = bsdf.continuation(values) if values else 0.0
    return rows


def _as_rows(value, kind):
    v = np.asarray(value, np.float64)
    if kind == "color":
        return np.broadcast_to(v, (1, 3)) if v.ndim < 2 and v.size in (1, 3) else v.reshape(-1, 3)
    return v.reshape(-1)


class MaterialTable:
    """The scene's materials in the packed form the kernels read; a shape refers to a row."""

    def __init__(self):
        self.rows = np.zeros(0, MATERIAL)
        self.names: dict[str, int] = {}

    def __len__(self):
        return len(self.rows)

    def add(self, material: Material, name: str = None) -> int:
        return int(self.add_rows(pack(material.type, material.params, material.emission,
                                      material.twosided), name)[0])

    def add_rows(self, rows: np.ndarray, name: str = None) -> np.ndarray:
        first = len(self.rows)
        self.rows = np.concatenate([self.rows, rows])
        if name is not None:
            self.names[name] = first
        return np.arange(first, first + len(rows))

    def get(self, index: int) -> Material:
        row = self.rows[index]
        type_name = list(BSDFS)[int(row["type"])]
        return Material(type_name, BSDFS[type_name].unpack(row), row["emission"][:3].astype(np.float64),
                        bool(row["flags"] & TWOSIDED))

    def set(self, index: int, material: Material):
        self.rows[index] = pack(material.type, material.params, material.emission, material.twosided)[0]

    def index(self, key) -> int:
        """The row of a material given by name (a scene file's named material) or by row."""
        if isinstance(key, str):
            if key not in self.names:
                raise UserError(f"no material named {short(key)} (named: {', '.join(self.names) or 'none'})")
            return self.names[key]
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)) or not -len(self) <= key < len(self):
            raise UserError(f"no material {short(key)}: give a name or a row from 0 to {len(self) - 1}")
        return int(key) % len(self)

    def __getitem__(self, key) -> Material:
        """table["gold"] or table[3]: the material as a Material, to change and assign back."""
        return self.get(self.index(key))

    def __setitem__(self, key, material: Material):
        self.set(self.index(key), material)

    def name_of(self, index: int) -> str | None:
        return next((n for n, i in self.names.items() if i == index), None)

    def copy(self) -> "MaterialTable":
        t = MaterialTable()
        t.rows, t.names = self.rows.copy(), dict(self.names)
        return t
