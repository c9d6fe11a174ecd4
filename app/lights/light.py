"""The interface every light type implements on the host. Area lights (emissive shapes) and the
environment come from the materials and the environment; the others are delta lights a scene
file names one by one (point, spot, directional), each a dataclass here with its parameters
declared once (app/parameters.py: their names in TOML, Mitsuba 3 and pbrt-v4, conversions and
defaults), its checks, its power (by which next-event estimation chooses it) and its slots in the
LIGHT struct (app/device/slots.py), which its kernel file kernels/lights/<name>.cl reads through the
accessors <NAME>_LIGHT_<SLOT>(l) generated from them (app/lights/registry.py: kernel_parts)."""

import dataclasses
import math

import numpy as np

from pathtrace.parameters import Parameter
from pathtrace.scene.environment import LUMINANCE
from pathtrace.device.slots import write_slot


class DeltaLight:
    """A light that no ray can hit: reached by next-event estimation only (kernels/lights.cl),
    and so dark in the estimator without it (RenderSettings.nee off)."""
    name: str
    parameters: tuple       # its Parameters (app/parameters.py), in the order scene files list them
    fields: tuple           # those of pathtrace's that are its dataclass fields (set from parameters)
    slots: tuple = ()       # its Slots (app/device/slots.py) in LIGHT's p0..p2: where its kernel reads
                            # each value; one named after a field holds that field's value
    formats: dict = {}      # its names in the other formats: {"mitsuba": name, "pbrt": name}
    unsupported: dict = {}  # {format: {name: why}}: what a format's light has and pathtrace has
                            # not, warned of where a file gives it
    # parameter sets, as a scene file's [[lights]] entry gives them (a spot may aim by look_at),
    # that the conformance suite (tests/test_light_conformance.py) renders with next-event
    # estimation, the light chosen by power and by the light tree; each type declares its own
    examples: tuple = ()

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.fields = tuple(p.name for p in cls.parameters if p.name in cls.__annotations__)

    @classmethod
    def from_values(cls, values: dict):
        """The light of a file's values (app/parameters.py: read), checked. Raises ValueError
        ("<parameter>: <problem>", or "missing '<parameter>'")."""
        values = cls.resolve(dict(values))
        missing = [name for name in cls.fields
                   if name not in values and cls.__dataclass_fields__[name].default is dataclasses.MISSING]
        if missing:
            raise ValueError(f"missing '{missing[0]}'")
        light = cls(**{k: v for k, v in values.items() if k in cls.fields})
        light.check()
        return light

    @classmethod
    def resolve(cls, values: dict) -> dict:
        """Turns the parameters that are another way to give one (a spot's look_at) into it."""
        return values

    def check(self):
        """Raises ValueError("<parameter>: <problem>") for the first parameter out of range."""

    def power(self, radius: float) -> float:
        """Its luminance power in watts; `radius` bounds the scene (for lights at infinity)."""

    def textures(self) -> list:
        """The Textures it reads (an image), which the scene's texture table holds."""
        return []

    def pack(self, row: np.ndarray, texture_rows: dict):
        """Fills a LIGHT row's slots: by default each field's value into the slot named after
        it (a type with slots of other values writes those too); texture_rows: {id(texture):
        its row of the texture table} of its textures()."""
        for slot in self.slots:
            if slot.name in self.fields:
                write_slot(row, slot.slot, getattr(self, slot.name))

    @classmethod
    def slot_of(cls, name: str) -> str:
        """The slot of one of its Slots, by name."""
        return next(s.slot for s in cls.slots if s.name == name)

    def tree_bounds(self):
        """Where and which way it shines, for the light tree (app/lights/tree.py): (point, cone
        axis, cos(theta_o), cos(theta_e)); None for a light at infinity, which the tree leaves
        out."""
        return None


def frame_quaternion(direction, up) -> np.ndarray:
    """The unit quaternion (x, y, z, w) of the rotation from a light's own space to the world's:
    its +z along `direction`, its +y along `up` made perpendicular to it, +x = y cross z
    (kernels/lights.cl: to_light_space turns a world direction back). Raises ValueError where up
    is (nearly) parallel to direction."""
    z = check_direction("direction", direction)
    u = check_direction("up", up)
    y = u - np.dot(u, z) * z
    if not np.linalg.norm(y) > 1e-6:
        raise ValueError("up: must not be parallel to direction")
    y /= np.linalg.norm(y)
    x = np.cross(y, z)
    m = np.column_stack([x, y, z])
    # Shepperd's method: the largest of 1 + trace and the diagonal's differences, for stability
    t = np.trace(m)
    k = int(np.argmax([t, m[0, 0], m[1, 1], m[2, 2]]))
    if k == 0:
        s = 2 * math.sqrt(1 + t)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4]
    else:
        i, j, l = k - 1, k % 3, (k + 1) % 3
        s = 2 * math.sqrt(1 + m[i, i] - m[j, j] - m[l, l])
        q = [0.0] * 4
        q[i], q[j], q[l], q[3] = s / 4, (m[j, i] + m[i, j]) / s, (m[l, i] + m[i, l]) / s, (m[l, j] - m[j, l]) / s
    return np.array(q)


def placed_in_frame(direction_doc: str, up_doc: str) -> tuple:
    """The Parameters of a point light with a frame of its own (goniometric, projection): its
    position, and its frame's +z (`direction`) and +y (`up`), by pbrt-v4's defaults those of its
    CTM (frame_quaternion)."""
    return (Parameter("position", "point", doc="where it is", pbrt_default=(0.0, 0.0, 0.0)),
            Parameter("direction", "vector", (0.0, 0.0, 1.0), doc=direction_doc, pbrt_default=(0.0, 0.0, 1.0)),
            Parameter("up", "vector", (0.0, 1.0, 0.0), doc=up_doc, pbrt_default=(0.0, 1.0, 0.0)))


def check_point(name: str, value) -> np.ndarray:
    v = np.asarray(value, np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)) or np.max(np.abs(v)) > 1e30:
        raise ValueError(f"{name}: must be three finite numbers, got {np.asarray(value).tolist()}")
    return v


def check_direction(name: str, value) -> np.ndarray:
    v = check_point(name, value)
    length = np.linalg.norm(v)
    if not length > 0:
        raise ValueError(f"{name}: must not be zero")
    return v / length


# The brightest radiance a scene may ask for (an emitter's, or the environment's texels times
# its intensity): a pixel's float32 sums of a million samples of it stay far below float32's
# 3.4e38, where 3e38, or 1e38 x 2, made every pixel +inf.
MAX_RADIANCE = 1e20


def check_color(name: str, value) -> np.ndarray:
    """A non-negative rgb value (a number is grey) below MAX_RADIANCE."""
    v = np.broadcast_to(np.asarray(value, np.float64), 3).copy()
    if not np.all(np.isfinite(v)) or np.any(v < 0) or np.max(v) > MAX_RADIANCE:
        bound = f"{MAX_RADIANCE:.0e}".replace("e+", "e")          # 1e20
        raise ValueError(f"{name}: must be three numbers in [0, {bound}], got {np.asarray(value).tolist()}")
    return v


def check_angle(name: str, value, high: float) -> float:
    if not 0 < value <= high or not math.isfinite(value):
        raise ValueError(f"{name}: must be in (0, {high:g}] degrees, got {value:g}")
    return float(value)


def luminance(rgb) -> float:
    return float(np.dot(rgb, LUMINANCE))


def pbrt_scaled(k_e):
    """The conversion of a pbrt-v4 light's spectrum: times its `scale`, and where `power` is given
    (> 0), times power / k_e, k_e(given) being the power of a unit spectrum (pbrt-v4's
    PointLight::Create and SpotLight::Create, src/pbrt/lights.cpp)."""
    def convert(value, given):
        value = np.asarray(value, np.float64) * given["scale"]
        return value * given["power"] / k_e(given) if given["power"] > 0 else value
    return convert


# pbrt-v4's parameters of every light, which become the others
PBRT_SCALE = Parameter(None, "number", pbrt="scale", pbrt_default=1.0, doc="a factor on the emitted spectrum")
PBRT_POWER = Parameter(None, "number", pbrt="power", pbrt_default=-1.0,
                       doc="the power in watts the light is scaled to, where positive")
