"""A scene: spheres with materials, an environment, a camera and render settings; read from a
TOML file (docs/scene-format.md) or built in (app/builtin_scenes.py)."""

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from app.camera import Camera
from app.environment import Environment
from app.errors import UserError
from app.resources import resource_dir


@dataclass
class RenderSettings:
    width: int = 960
    height: int = 540
    spp: int = 64
    max_depth: int = 0            # 0: paths end by Russian roulette alone
    russian_roulette: bool = True
    seed: int = 0
    nee: bool = True              # next-event estimation with MIS; off: the report's estimator


@dataclass
class Scene:
    name: str
    spheres: np.ndarray           # (N, 4) float32: centre, radius
    rho_d: np.ndarray             # (N, 3) diffuse albedo
    rho_s: np.ndarray             # (N, 3) glossy albedo
    exponent: np.ndarray          # (N,) Phong exponent
    emission: np.ndarray          # (N, 3) emitted radiance
    camera: Camera = field(default_factory=Camera)
    environment: Environment = field(default_factory=lambda: Environment.constant((1, 1, 1)))
    settings: RenderSettings = field(default_factory=RenderSettings)

    def with_settings(self, **changes) -> "Scene":
        return replace(self, settings=replace(self.settings, **changes))


class SceneBuilder:
    """Collects spheres one material at a time; the built-in scenes and the file reader use it."""

    def __init__(self):
        self.spheres, self.rho_d, self.rho_s, self.exponent, self.emission = [], [], [], [], []

    def add(self, center, radius, rho_d=(0, 0, 0), rho_s=(0, 0, 0), exponent=1.0, emission=(0, 0, 0)):
        self.spheres.append((*center, radius))
        self.rho_d.append(np.broadcast_to(rho_d, 3))
        self.rho_s.append(np.broadcast_to(rho_s, 3))
        self.exponent.append(exponent)
        self.emission.append(np.broadcast_to(emission, 3))

    def build(self, name, **kwargs) -> Scene:
        f32 = lambda a, shape: np.asarray(a, np.float32).reshape(shape)  # noqa: E731
        return Scene(name, f32(self.spheres, (-1, 4)), f32(self.rho_d, (-1, 3)),
                     f32(self.rho_s, (-1, 3)), f32(self.exponent, (-1,)),
                     f32(self.emission, (-1, 3)), **kwargs)


# ---------------------------------------------------------------------------------------------
# Reading scene files. Every check names the file and the field, e.g.
#   scenes/room.toml: spheres[3].radius: must be positive, got -1

_MATERIAL_KEYS = {
    "diffuse": {"type", "rho_d"},
    "phong": {"type", "rho_d", "rho_s", "n"},
    "emitter": {"type", "Le"},
}


class _Reader:
    def __init__(self, path: Path):
        self.path = path

    def fail(self, where, problem):
        raise UserError(f"{self.path}: {where}: {problem}")

    def table(self, data, where, allowed):
        if not isinstance(data, dict):
            self.fail(where, f"must be a table, got {type(data).__name__}")
        unknown = sorted(set(data) - set(allowed))
        if unknown:
            self.fail(where, f"unknown key '{unknown[0]}' (allowed: {', '.join(sorted(allowed))})")
        return data

    def number(self, data, key, where, default=None, low=None, high=None, integer=False):
        if key not in data:
            if default is None:
                self.fail(where, f"missing '{key}'")
            return default
        value = data[key]
        kinds = (int,) if integer else (int, float)
        if isinstance(value, bool) or not isinstance(value, kinds):
            self.fail(f"{where}.{key}", f"must be {'an integer' if integer else 'a number'}, got {value!r}")
        if not math.isfinite(value):
            self.fail(f"{where}.{key}", f"must be finite, got {value}")
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
            self.fail(f"{where}.{key}", f"must be a number or a list of 3 numbers, got {value!r}")
        for c in items:
            if isinstance(c, bool) or not isinstance(c, (int, float)) or not math.isfinite(c):
                self.fail(f"{where}.{key}", f"must hold finite numbers, got {value!r}")
            if c < 0 or (high is not None and c > high):
                bound = f"in [0, {high}]" if high is not None else "non-negative"
                self.fail(f"{where}.{key}", f"must be {bound}, got {value!r}")
        return np.asarray(items, np.float64)

    def vector(self, data, key, where, default=None):
        if key not in data:
            if default is None:
                self.fail(where, f"missing '{key}'")
            return np.asarray(default, np.float64)
        value = data[key]
        if (not isinstance(value, list) or len(value) != 3
                or not all(isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
                           for c in value)):
            self.fail(f"{where}.{key}", f"must be a list of 3 finite numbers, got {value!r}")
        return np.asarray(value, np.float64)

    def material(self, data, where):
        if not isinstance(data, dict):
            self.fail(where, f"must be a table, got {data!r}")
        kind = data.get("type")
        if kind not in _MATERIAL_KEYS:
            self.fail(f"{where}.type", f"must be one of {', '.join(_MATERIAL_KEYS)}, got {kind!r}")
        self.table(data, where, _MATERIAL_KEYS[kind])
        zero = np.zeros(3)
        if kind == "emitter":
            return dict(emission=self.color(data, "Le", where))
        rho_d = self.color(data, "rho_d", where, high=1)
        if kind == "diffuse":
            return dict(rho_d=rho_d)
        rho_s = self.color(data, "rho_s", where, default=zero, high=1)
        exponent = self.number(data, "n", where, low=0)
        if np.any(rho_d + rho_s > 1 + 1e-6):
            self.fail(where, f"rho_d + rho_s must not exceed 1 in any channel (energy conservation), "
                             f"got {list(np.round(rho_d + rho_s, 6))}")
        return dict(rho_d=rho_d, rho_s=rho_s, exponent=exponent)

    def camera(self, data):
        where = "camera"
        self.table(data, where, {"eye", "look_at", "up", "vfov"})
        cam = Camera(self.vector(data, "eye", where), self.vector(data, "look_at", where),
                     self.vector(data, "up", where, default=(0, 1, 0)),
                     self.number(data, "vfov", where, default=45.0))
        if not 0 < cam.vfov < 180:
            self.fail("camera.vfov", f"must be between 0 and 180 degrees, got {cam.vfov}")
        forward = cam.look_at - cam.eye
        if np.linalg.norm(forward) == 0:
            self.fail("camera.look_at", "must differ from camera.eye")
        if np.linalg.norm(np.cross(forward, cam.up)) < 1e-9 * np.linalg.norm(forward) * np.linalg.norm(cam.up):
            self.fail("camera.up", "must not be parallel to the view direction")
        return cam

    def environment(self, data):
        where = "environment"
        self.table(data, where, {"color", "map", "intensity", "rotation"})
        intensity = self.number(data, "intensity", where, default=1.0, low=0)
        rotation = self.number(data, "rotation", where, default=0.0)
        if "map" in data and "color" in data:
            self.fail(where, "give either 'color' or 'map', not both")
        if "map" in data:
            name = data["map"]
            if not isinstance(name, str):
                self.fail("environment.map", f"must be a file name, got {name!r}")
            return Environment.from_file(self.find_asset(name), intensity, rotation,
                                         where=f"{self.path}: environment.map")
        env = Environment.constant(self.color(data, "color", where, default=(1, 1, 1)), intensity)
        env.rotation = rotation
        return env

    def find_asset(self, name):
        """A map path is relative to the scene file; a bare name may also be a shipped map."""
        candidate = (self.path.parent / name)
        if candidate.exists():
            return candidate
        shipped = resource_dir("assets") / "envmaps" / name
        return shipped if shipped.exists() else candidate

    def settings(self, data):
        where = "render"
        self.table(data, where, {"width", "height", "spp", "max_depth", "russian_roulette", "seed", "nee"})
        rr, nee = data.get("russian_roulette", True), data.get("nee", True)
        for key, value in (("russian_roulette", rr), ("nee", nee)):
            if not isinstance(value, bool):
                self.fail(f"render.{key}", f"must be true or false, got {value!r}")
        s = RenderSettings(
            width=self.number(data, "width", where, default=960, low=1, high=16384, integer=True),
            height=self.number(data, "height", where, default=540, low=1, high=16384, integer=True),
            spp=self.number(data, "spp", where, default=64, low=1, integer=True),
            max_depth=self.number(data, "max_depth", where, default=0, low=0, integer=True),
            russian_roulette=rr, nee=nee,
            seed=self.number(data, "seed", where, default=0, low=0, high=2**32 - 1, integer=True))
        if not s.russian_roulette and s.max_depth == 0:
            self.fail("render.russian_roulette", "false needs a max_depth above 0, or paths never end")
        return s

    def scene(self, data) -> Scene:
        self.table(data, "top level", {"camera", "environment", "render", "materials", "spheres"})
        materials = {}
        named = data.get("materials", {})
        self.table(named, "materials", set(named) if isinstance(named, dict) else set())
        for name, m in named.items():
            materials[name] = self.material(m, f"materials.{name}")
        spheres = data.get("spheres")
        if not isinstance(spheres, list) or not spheres:
            self.fail("spheres", "the scene needs at least one [[spheres]] entry")
        builder = SceneBuilder()
        for i, s in enumerate(spheres):
            where = f"spheres[{i}]"
            self.table(s, where, {"center", "radius", "material"})
            center = self.vector(s, "center", where)
            radius = self.number(s, "radius", where)
            if radius <= 0:
                self.fail(f"{where}.radius", f"must be positive, got {radius}")
            m = s.get("material")
            if isinstance(m, str):
                if m not in materials:
                    self.fail(f"{where}.material", f"no material named '{m}' in [materials]")
                params = materials[m]
            elif m is None:
                self.fail(where, "missing 'material'")
            else:
                params = self.material(m, f"{where}.material")
            builder.add(center, radius, **params)
        return builder.build(
            self.path.stem,
            camera=self.camera(data.get("camera", {"eye": [0, 0, 5], "look_at": [0, 0, 0]})),
            environment=self.environment(data.get("environment", {})),
            settings=self.settings(data.get("render", {})))


def read_scene_file(path) -> Scene:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise UserError(f"{path}: no such scene file") from None
    except (OSError, UnicodeDecodeError) as e:
        raise UserError(f"{path}: cannot read the scene file ({e})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UserError(f"{path}: not valid TOML: {e}") from None
    return _Reader(path).scene(data)


def load_scene(name_or_path: str) -> Scene:
    """A scene file path or a built-in scene's name: the two are interchangeable."""
    from app.builtin_scenes import BUILTIN_SCENES, builtin_scene

    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        return read_scene_file(path)
    scene = builtin_scene(name_or_path)
    if scene is not None:
        return scene
    raise UserError(f"{name_or_path}: neither a scene file nor a built-in scene "
                    f"(built-ins: {', '.join(BUILTIN_SCENES)})")
