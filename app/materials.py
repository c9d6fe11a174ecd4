"""The materials: a registry of BSDF types, each with its parameters (Mitsuba 3's names where
Mitsuba has the material), their checks, and how they pack into the MATERIAL struct that its
kernel file kernels/bsdfs/<name>.cl reads. The registry also gives each type its tag and
generates the kernels' dispatch (eval_bsdf, pdf_bsdf, sample_bsdf), so that adding a material
is one kernel file and one entry here.

A scene's materials live in a MaterialTable: the packed rows the kernels read, with named
entries and per-row access to the parameters (the viewer's editor)."""

from dataclasses import dataclass, field

import numpy as np

from app.types import MATERIAL

# MATERIAL.flags bits, as kernels/bsdf.cl defines them
TWOSIDED = 1
DELTA = 2


@dataclass(frozen=True)
class Param:
    name: str
    kind: str                 # "color" (a number or three) or "number"
    default: object = None    # None: required
    low: float = 0.0
    high: float = None        # None: unbounded
    doc: str = ""


class BSDFType:
    """One material type. Subclasses set name, params and doc, and define pack/unpack over
    arrays whose leading axis is the row (so that a scene of 10^6 random spheres packs at once)."""
    name: str
    params: tuple = ()
    doc: str = ""
    flags: int = 0            # DELTA where every lobe is a delta
    kernel: bool = True       # has kernels/bsdfs/<name>.cl

    def check(self, values: dict) -> str | None:
        """A problem with a combination of values, or None."""
        return None

    def pack(self, values: dict, rows: np.ndarray):
        raise NotImplementedError

    def unpack(self, row) -> dict:
        raise NotImplementedError

    def continuation(self, values: dict) -> np.ndarray:
        """The probability with which the report's Russian roulette goes on from this material:
        an estimate of its albedo, at most 1."""
        return np.ones(len(next(iter(values.values()))))


class Black(BSDFType):
    name = "black"
    doc = "reflects nothing; with Le an emitter (the `emitter` type of scene files)"
    kernel = False

    def pack(self, values, rows):
        pass

    def unpack(self, row):
        return {}


class Diffuse(BSDFType):
    name = "diffuse"
    params = (Param("rho_d", "color", high=1.0, doc="albedo (Mitsuba: reflectance)"),)
    doc = "Lambertian, f = rho_d / pi"

    def pack(self, values, rows):
        rows["p0"][:, :3] = values["rho_d"]

    def unpack(self, row):
        return {"rho_d": row["p0"][:3].copy()}

    def continuation(self, values):
        return np.max(values["rho_d"], axis=-1)


class Phong(BSDFType):
    name = "phong"
    params = (Param("rho_d", "color", high=1.0, doc="diffuse albedo"),
              Param("rho_s", "color", default=0.0, high=1.0, doc="glossy albedo"),
              Param("n", "number", doc="Phong exponent"))
    doc = ("modified Phong (Lafortune & Willems 1994), f = rho_d / pi + rho_s (n + 2) / (2 pi) "
           "cos^n(alpha); rho_d + rho_s <= 1 in each channel")

    def check(self, values):
        total = values["rho_d"] + values["rho_s"]
        if np.any(total > 1 + 1e-6):
            return (f"rho_d + rho_s must not exceed 1 in any channel (energy conservation), "
                    f"got {[round(float(x), 6) for x in np.ravel(total)[:3]]}")
        return None

    @staticmethod
    def lobe_albedos(values):
        return np.max(values["rho_d"], axis=-1), np.max(values["rho_s"], axis=-1)

    def pack(self, values, rows):
        p_d, p_s = self.lobe_albedos(values)
        total = p_d + p_s
        # a black Phong material never samples; give it a harmless diffuse choice
        rows["p0"][:, :3] = values["rho_d"]
        rows["p0"][:, 3] = np.where(total > 0, p_d / np.where(total > 0, total, 1), 1.0)
        rows["p1"][:, :3] = values["rho_s"]
        rows["p1"][:, 3] = values["n"]
        rows["p2"][:, 0] = 1.0 - rows["p0"][:, 3]

    def unpack(self, row):
        return {"rho_d": row["p0"][:3].copy(), "rho_s": row["p1"][:3].copy(), "n": float(row["p1"][3])}

    def continuation(self, values):
        p_d, p_s = self.lobe_albedos(values)
        return np.minimum(p_d + p_s, 1.0)


BSDFS = {cls.name: cls() for cls in (Black, Diffuse, Phong)}
TAGS = {name: i for i, name in enumerate(BSDFS)}


def dispatch_source() -> str:
    """The BSDF_<NAME> tags and the eval/pdf/sample dispatch of kernels/bsdf.cl."""
    tags = "".join(f"#define BSDF_{name.upper()} {TAGS[name]}\n" for name in BSDFS)
    with_kernel = [n for n, b in BSDFS.items() if b.kernel]

    def switch(ret, call, default):
        cases = "".join(f"    case BSDF_{n.upper()}: return {call.format(n)};\n" for n in with_kernel)
        return f"    switch (m->type) {{\n{cases}    default: return {default};\n    }}\n"
    return (tags
            + "float3 eval_bsdf(const global Material *m, float3 wo, float3 wi)\n{\n"
            + switch("float3", "eval_{}(m, wo, wi)", "(float3)(0.0f)") + "}\n"
            + "float pdf_bsdf(const global Material *m, float3 wo, float3 wi)\n{\n"
            + switch("float", "pdf_{}(m, wo, wi)", "0.0f") + "}\n"
            + "int sample_bsdf(const global Material *m, float3 wo, float3 u, BSDFSample *s)\n{\n"
            + switch("int", "sample_{}(m, wo, u, s)", "0") + "}\n")


def kernel_files() -> list[str]:
    return [f"bsdfs/{n}.cl" for n, b in BSDFS.items() if b.kernel]


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
    or an (N,) array."""
    bsdf = BSDFS[type_name]
    values = {p.name: _as_rows(params.get(p.name, p.default), p.kind) for p in bsdf.params}
    emission = _as_rows(emission, "color")
    lengths = [len(v) for v in values.values()] + [len(emission)]
    n = 0 if 0 in lengths else max(lengths)
    values = {k: np.broadcast_to(v, (n,) + v.shape[1:]) for k, v in values.items()}
    rows = np.zeros(n, MATERIAL)
    bsdf.pack(values, rows)
    rows["emission"][:, :3] = emission
    rows["type"] = TAGS[type_name]
    rows["flags"] = bsdf.flags | (TWOSIDED if twosided else 0)
    rows["continuation"] = bsdf.continuation(values) if bsdf.params else 0.0
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

    def name_of(self, index: int) -> str | None:
        return next((n for n, i in self.names.items() if i == index), None)

    def copy(self) -> "MaterialTable":
        t = MaterialTable()
        t.rows, t.names = self.rows.copy(), dict(self.names)
        return t
