"""A scene's materials: the packed MATERIAL rows the kernels read, with named entries and
per-row access to the parameters (the viewer's editor). A parameter may be a texture: its row
holds its mean (app/materials/bsdf.py: constant_of), and the row's bindings say which texture
gives the parameter's slot at each hit (app/textures/table.py compiles them)."""

from dataclasses import dataclass, field, replace

import numpy as np

from pathtrace.errors import UserError, short
from pathtrace.materials.blend import MAX_BLEND_DEPTH
from pathtrace.materials.bsdf import EMITS_BACK, MASKED, NULL, PBRT_PERTURBATION, TRANSMISSIVE, TWOSIDED, constant_of
from pathtrace.materials.registry import BSDFS, TAGS
from pathtrace.parameters import out_of_range
from pathtrace.device.slots import read_slot, write_slot
from pathtrace.textures.texture import Texture
from pathtrace.device.types import MATERIAL


# The two conventions of a normal or bump map (kernels/normal_maps.cl: perturb_normal). Mitsuba 3's:
# a perturbed normal that faces away from the outgoing direction has its tangential part turned
# round, and the light is weighed by the shadow-terminator term. pbrt-v4's: the normal is turned
# to the geometric normal's side (SurfaceInteraction::SetShadingGeometry's FaceForward), with no
# such term (materials.h: NormalMap, BumpMap). The readers of each format choose its own.
PERTURBATIONS = ("mitsuba", "pbrt")


@dataclass
class Material:
    """One material as a scene file states it; parameters with a slot (Param.slot) and the
    emission may be Textures."""
    type: str
    params: dict = field(default_factory=dict)
    emission: np.ndarray = field(default_factory=lambda: np.zeros(3))
    twosided: bool = False
    opacity: object = 1.0         # an alpha mask: the probability that a ray meets the surface,
                                  # a number or a Texture (kernels/masks.cl)
    normal_map: Texture = None    # a tangent-space normal map, or a bump map (a height field: a
    bump_map: Texture = None      # bitmap, or a scale of one), kernels/normal_maps.cl
    components: tuple = ()        # a blendbsdf's two Materials (app/materials/blend.py)
    emits_back: bool = False      # the emission leaves both sides (pbrt's twosided area light)
    perturbation: str = "mitsuba"  # how a normal or bump map perturbs (PERTURBATIONS)

    @property
    def masked(self) -> bool:
        return isinstance(self.opacity, Texture) or float(self.opacity) < 1.0

    def textures(self) -> list:
        """(parameter, first float of its slot, width, Texture) of each textured parameter, the
        emission's as "emission" and the opacity's (a constant one as a constant texture) as
        "opacity"."""
        out = []
        for p in BSDFS[self.type].params:
            value = self.params.get(p.name)
            if isinstance(value, Texture):
                out.append((p.name, *slot_index(p.slot), value))
        if isinstance(self.emission, Texture):
            out.append(("emission", *slot_index("emission.xyz"), self.emission))
        if self.masked:
            opacity = self.opacity if isinstance(self.opacity, Texture) else \
                Texture("constant", {"value": np.full(3, float(self.opacity)), "to_uv": np.eye(3)})
            out.append(("opacity", *slot_index("opacity.x"), opacity))
        if self.normal_map is not None:
            out.append(("normal_map", *slot_index("normal_map.xyz"), self.normal_map))
        if self.bump_map is not None:
            check_bump_map(self.bump_map)
            out.append(("bump_map", *slot_index("bump_map.x"), self.bump_map))
        return out

    def constants(self) -> tuple:
        """(params, emission) with each texture replaced by its mean."""
        kinds = {p.name: p.kind for p in BSDFS[self.type].params}
        return ({k: constant_of(v, kinds.get(k, "number")) for k, v in self.params.items()},
                constant_of(self.emission, "color"))


# kernels/shading.cl, masks.cl, normal_maps.cl
def check_bump_map(texture: Texture):
    """A bump map's slopes are the analytic gradient of a bitmap (Mitsuba's eval_1_grad), times
    a constant factor: a bitmap, or a scale of one by a number. Raises ValueError."""
    inner, factor = texture, None
    if texture.type == "scale":
        inner, factor = texture.params["tex"], texture.params["scale"]
    if not isinstance(inner, Texture) or inner.type != "bitmap" or isinstance(factor, Texture):
        raise ValueError("a bump map must be a bitmap texture, or a scale of one by a number")


def scaled_bump_map(texture: Texture, scale: float) -> Texture:
    """The bump map of heights `texture` times `scale`, checked (check_bump_map): the map itself
    first, as a scale of a texture that combines others cannot be built. Raises ValueError."""
    check_bump_map(texture)
    if scale == 1.0:
        return texture
    from pathtrace.textures import TEXTURES
    scaled = Texture("scale", TEXTURES["scale"].complete({"tex": texture, "scale": scale}))
    check_bump_map(scaled)
    return scaled


def surface_problem(material: Material) -> tuple | None:
    """(the field of app/materials/surface.py's SURFACE, the problem) of what a Material carries
    that cannot go with its BSDF or each other, or None: the check of the readers (dressed), which
    name the field, and of the table (MaterialTable.set), whatever made the Material."""
    if material.normal_map is not None and material.bump_map is not None:
        return "normal_map", "give a normal_map or a bump_map, not both"
    if material.twosided and transmits(material):
        # Mitsuba 3 refuses the combination too: a transmissive BSDF already has two sides, and
        # turning its frame round for back hits would send light through glass the wrong way
        return "twosided", f"a {material.type} cannot be two-sided: it transmits, and is seen from both sides already"
    if BSDFS[material.type].flags & NULL and (isinstance(material.emission, Texture) or np.any(material.emission > 0)):
        return "Le", "a null material is no surface, and cannot emit"
    return None


def value_problem(material: Material) -> ValueError | None:
    """The first of a Material's values outside its BSDF's declared ranges, or an emission not
    finite or negative, its blend components' included, as a ValueError ("<name>: <problem>"):
    the check the readers make as they read, for a Material a user changed (the API's
    `scene.materials[key] = m`)."""
    from pathtrace.lights.light import MAX_RADIANCE      # (pathtrace.lights imports this module)
    emission = material.emission
    if not isinstance(emission, Texture) and not np.all((np.asarray(emission, np.float64) <= MAX_RADIANCE) &
                                                        (np.asarray(emission, np.float64) >= 0)):
        # (NaN fails both) beyond MAX_RADIANCE the float32 sums of samples overflow, and the row's float32 cast
        return ValueError(f"emission: must lie in [0, {MAX_RADIANCE:g}], got {np.asarray(emission).tolist()}")
    error = out_of_range(BSDFS[material.type].params, material.params) if material.type in BSDFS else None
    return error or next((e for e in map(value_problem, material.components or ()) if e), None)


def blend(weight, components: tuple) -> "Material":
    """A blendbsdf of two Materials, the second taken with probability `weight` (a number or a
    texture; None: the declared default), checked. Raises ValueError ("weight: <problem>", or
    check_blend's)."""
    given = {} if weight is None else {"weight": weight}
    error = out_of_range(BSDFS["blendbsdf"].params, given)
    if error:
        raise error
    material = Material("blendbsdf", BSDFS["blendbsdf"].complete(given), components=tuple(components))
    problem = check_blend(material)
    if problem:
        raise ValueError(problem)
    return material


# blends (app/materials/blend.py): their components are Materials, checked and packed here, where
# every type of the registry is known
def depth(material) -> int:
    """How deep blends nest in a Material: 0 for any other type."""
    if material.type != "blendbsdf":
        return 0
    return 1 + max((depth(c) for c in material.components), default=0)


def transmits(material) -> bool:
    """Whether a Material is seen from both sides (a transmissive one, or a blend of them)."""
    if material.type == "blendbsdf":
        return any(transmits(c) for c in material.components)
    return BSDFS[material.type].transmits(material.params)


def check_blend(material) -> str | None:
    """A problem with a blend's components, or None."""
    if len(material.components) != 2:
        return f"a blendbsdf mixes two materials, got {len(material.components)}"
    for c in material.components:
        if BSDFS[c.type].flags & NULL:
            return "a blendbsdf cannot mix in a null material (no surface)"
        if c.masked:
            return "the materials a blendbsdf mixes cannot have an opacity: give the blend one"
    if depth(material) > MAX_BLEND_DEPTH:
        return f"blendbsdfs nest deeper than {MAX_BLEND_DEPTH}"
    if len({transmits(c) for c in material.components}) > 1:
        return "a blendbsdf cannot mix a transmissive material with a one-sided one"
    return None


def components_of(rows) -> np.ndarray:
    """The rows of the two components of blend rows (MATERIAL rows, or one), as (n, 2) (or (2,)),
    from the slots the blend declares (app/materials/blend.py)."""
    slots = BSDFS["blendbsdf"].slots()
    return np.stack([read_slot(rows, slots["first"]), read_slot(rows, slots["second"])], axis=-1).astype(np.int64)


def set_components(rows: np.ndarray, components):
    """Writes the rows of a blend's two components into its MATERIAL rows."""
    slots = BSDFS["blendbsdf"].slots()
    write_slot(rows, slots["first"], components[0])
    write_slot(rows, slots["second"], components[1])


def component_rows(rows: np.ndarray) -> np.ndarray:
    """The rows of the two components of each blend among `rows` (MATERIAL rows)."""
    return components_of(rows[rows["type"] == TAGS["blendbsdf"]]).ravel()


def reachable(table_rows: np.ndarray, used) -> np.ndarray:
    """The rows `used` (indices of table_rows, one per primitive) and every row their blends
    choose from, in order."""
    found = np.flatnonzero(np.bincount(np.asarray(used, np.int64).ravel(), minlength=len(table_rows)))
    blends = table_rows["type"] == TAGS["blendbsdf"]
    while True:
        # the blends' rows alone are gathered: a table of a million materials (spheres1M) without
        # blends had every row copied and sorted again, 0.3 s a call
        chosen = found[blends[found]]
        more = np.union1d(found, components_of(table_rows[chosen]).ravel()) if len(chosen) else found
        if len(more) == len(found):
            return found
        found = more


_FIELDS = {"p0": 0, "p1": 4, "p2": 8, "emission": 12, "opacity": 16, "normal_map": 20, "bump_map": 24}


def slot_index(slot: str) -> tuple:
    """(first float, width) of a slot such as "p0.xyz" (0, 3) or "p1.w" (7, 1)."""
    field_name, components = slot.split(".")
    return _FIELDS[field_name] + "xyzw".index(components[0]), len(components)


def pack(type_name: str, params: dict, emission=(0, 0, 0), twosided=False, emits_back=False) -> np.ndarray:
    """Rows of MATERIAL for one type. Each parameter and the emission hold one value for all
    rows or one per row: a colour is a number, 3 numbers or an (N, 3) array, a number a scalar
    or an (N,) array. Names are resolved (BSDFType.resolve), and parameters left out take their
    defaults. Raises ValueError for a parameter the type does not have (a format's name for
    one it has: Mitsuba's "reflectance" for rho_d) and for one left out that has no default,
    which would be packed as NaN (np.asarray(None, float)): the kernels drop the samples of the
    paths that meet such a material, each estimator different ones, so that they disagree as if
    one of them were biased. What the type cannot go with (a two-sided transmitter) is the
    table's to refuse (MaterialTable.set: surface_problem), which packs each row through here."""
    bsdf = BSDFS[type_name]
    known = [p.name for p in bsdf.params]
    unknown = sorted(set(params) - set(known))
    if unknown:
        raise ValueError(f"{type_name}: unknown parameter '{unknown[0]}' "
                         f"(its parameters: {', '.join(known) or 'none'})")
    params = bsdf.resolve(params)
    missing = [p.name for p in bsdf.params if p.kind != "name" and p.into is None and p.default is None
               and p.name not in params]
    if missing:
        raise ValueError(f"{type_name}: missing '{missing[0]}'")
    emission = _as_rows(emission, "color")
    values = {p.name: _as_rows(params.get(p.name, p.default), p.kind)
              for p in bsdf.params if p.kind != "name" and p.into is None}
    lengths = [len(v) for v in values.values()] + [len(emission)]
    n = 0 if 0 in lengths else max(lengths)
    values = {k: np.broadcast_to(v, (n,) + v.shape[1:]) for k, v in values.items()}
    rows = np.zeros(n, MATERIAL)
    bsdf.pack(values, rows)
    rows["emission"][:, :3] = emission
    rows["type"] = TAGS[type_name]
    rows["flags"] = bsdf.row_flags(values, n) | (TWOSIDED if twosided else 0) | (EMITS_BACK if emits_back else 0)
    rows["continuation"] = bsdf.continuation(values) if values else 0.0
    rows["textures"] = -1
    return rows


def _as_rows(value, kind):
    v = np.asarray(value, np.float64)
    if kind == "color":
        return np.broadcast_to(v, (1, 3)) if v.ndim < 2 and v.size in (1, 3) else v.reshape(-1, 3)
    return v.reshape(-1)


class MaterialTable:
    """The scene's materials in the packed form the kernels read; a shape refers to a row. Read
    as a mapping: its keys are the rows' names, or their numbers where they have none."""

    def __init__(self):
        self.rows = np.zeros(0, MATERIAL)
        self.names: dict[str, int] = {}
        self.textures: list = []     # per row: Material.textures() of its material

    def __len__(self):
        return len(self.rows)

    def add(self, material: Material, name: str = None) -> int:
        row = int(self.add_rows(np.zeros(1, MATERIAL), name)[0])
        self.set(row, material)
        return row

    def add_rows(self, rows: np.ndarray, name: str = None) -> np.ndarray:
        first, end = len(self.rows), len(self.rows) + len(rows)
        spare = self.rows.base
        if spare is None or spare.dtype != MATERIAL or spare.ndim != 1 or len(spare) < end:
            # rows are the start of a larger array, grown geometrically, so that a reader adding
            # a row per shape (20,000 pbrt attribute blocks) takes linear time, not quadratic
            spare = np.zeros(max(end, 2 * first, 16), MATERIAL)
            spare[:first] = self.rows
        spare[first:end] = rows
        self.rows = spare[:end]
        self.textures += [[] for _ in range(len(rows))]
        if name is not None:
            self.names[name] = first
        return np.arange(first, first + len(rows))

    def get(self, index: int) -> Material:
        row = self.rows[index]
        type_name = list(BSDFS)[int(row["type"])]
        material = Material(type_name, BSDFS[type_name].unpack(row), row["emission"][:3].astype(np.float64),
                            bool(row["flags"] & TWOSIDED),
                            emits_back=bool(row["flags"] & EMITS_BACK),
                            perturbation=PERTURBATIONS[bool(row["flags"] & PBRT_PERTURBATION)])
        for name, _, _, texture in self.textures[index]:
            if name in ("emission", "opacity", "normal_map", "bump_map"):
                setattr(material, name, texture)
            else:
                material.params[name] = texture
        if type_name == "blendbsdf":
            material.components = tuple(replace(self.get(int(r)), emission=np.zeros(3), twosided=False, emits_back=False,
                                                normal_map=None, bump_map=None) for r in components_of(row))
        return material

    def reads_frame(self, index: int) -> bool:
        """Whether row `index` reads a surface's texture coordinates or tangents: a texture (an
        alpha mask, a normal or bump map among them), or a variant whose kernels take the
        tangent frame (anisotropic roughness) or whose components may (a blend)."""
        row = self.rows[index:index + 1]
        type_name = list(BSDFS)[int(row["type"][0])]
        return bool(self.textures[index]) or bool({"ANISOTROPIC", "BLEND"} & set(BSDFS[type_name].defines(row)))

    def set(self, index: int, material: Material):
        problem = surface_problem(material)      # its one check here: pack makes none
        if problem:
            raise ValueError(problem[1])
        params, emission = material.constants()
        rows = pack(material.type, params, emission, material.twosided, material.emits_back)
        if material.masked:
            rows["flags"] |= MASKED
        if material.perturbation not in PERTURBATIONS:
            raise ValueError(f"perturbation must be one of {', '.join(PERTURBATIONS)}, got {material.perturbation!r}")
        if material.perturbation == "pbrt":
            rows["flags"] |= PBRT_PERTURBATION
        if material.type == "blendbsdf":
            components = self._set_components(index, material)
            set_components(rows, components)
            rows["flags"] |= self.rows[components[0]]["flags"] & TRANSMISSIVE
        self.rows[index] = rows[0]
        self.textures[index] = material.textures()

    def _set_components(self, index: int, material: Material) -> list:
        """The rows of a blend's components, its own (those it had, or new ones), each with
        the blend's emission, sides and shading maps (the kernels shade the component a hit
        takes)."""
        problem = check_blend(material)
        if problem:
            raise ValueError(problem)
        old = self.rows[index]
        rows = [int(r) for r in components_of(old)] if old["type"] == TAGS["blendbsdf"] else [None, None]
        for k, c in enumerate(material.components):
            c = replace(c, emission=material.emission, twosided=material.twosided, emits_back=material.emits_back,
                        normal_map=material.normal_map, bump_map=material.bump_map, perturbation=material.perturbation)
            if rows[k] is None:
                rows[k] = self.add(c)
            else:
                self.set(rows[k], c)
        return rows

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
        if not isinstance(material, Material):
            raise UserError(f"materials[{short(key)}]: give a pathtrace.Material (pathtrace.material({{...}}) "
                            f"makes one), got {short(material)}")
        try:
            error = value_problem(material)
            if error:
                raise error
            self.set(self.index(key), material)
        except ValueError as e:     # a value out of range, a parameter it lacks or left out (pack), a combination refused
            raise UserError(f"materials[{short(key)}]: {e}") from None

    def keys(self) -> list:
        """Each row's name, or its number where it has none, in row order."""
        named = {}
        for name, row in self.names.items():
            named.setdefault(row, name)
        return [named.get(i, i) for i in range(len(self))]

    def __iter__(self):
        return iter(self.keys())

    def values(self) -> list:
        return [self.get(i) for i in range(len(self))]

    def items(self) -> list:
        return list(zip(self.keys(), self.values()))

    def __contains__(self, key) -> bool:
        if isinstance(key, str):
            return key in self.names
        return not isinstance(key, bool) and isinstance(key, (int, np.integer)) and -len(self) <= key < len(self)

    def __repr__(self) -> str:
        from pathtrace.scene.named import summary
        types = [list(BSDFS)[int(t)] for t in self.rows["type"]]
        return f"<{len(self)} material{'' if len(self) == 1 else 's'}" + (
            f": {summary(f'{k} ({t})' for k, t in zip(self.keys(), types))}>" if len(self) else ">")

    def all_textures(self) -> list:
        """Every texture the materials use, their inputs included, each once."""
        found, todo = {}, [entry[3] for entries in self.textures for entry in entries]
        while todo:
            t = todo.pop()
            if id(t) not in found:
                found[id(t)] = t
                todo += t.inputs()
        return list(found.values())

    def texel_bytes(self) -> int:
        """An upper bound of the bytes the textures' images take on a device (an rgb image is
        stored as rgba there)."""
        images = {id(t.params["image"]): t.params["image"].texels for t in self.all_textures() if "image" in t.params}
        return sum(a.nbytes * (4 if a.shape[2] == 3 else a.shape[2]) // a.shape[2] for a in images.values())

    def name_of(self, index: int) -> str | None:
        return next((n for n, i in self.names.items() if i == index), None)

    def copy(self) -> "MaterialTable":
        t = MaterialTable()
        t.rows, t.names, t.textures = self.rows.copy(), dict(self.names), [list(b) for b in self.textures]
        return t
