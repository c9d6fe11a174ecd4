"""The environment: a constant colour or an HDR latitude-longitude map, with an intensity and an
orientation: the world direction of the map's zenith (`up`) and a turn about it (`rotation`)
(kernels/environment.cl gives the mapping); and its parameters in the three formats:
pathtrace's [environment], Mitsuba 3's `constant` and `envmap` emitters, pbrt-v4's `infinite`
light (app/parameters.py; the readers place a map by the element's to_world or CTM, and pbrt-v4's
equal-area square becomes a latitude-longitude map)."""

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pathtrace.parameters import Parameter

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])   # Rec. 709 weights of linear R, G, B


def world_from_map(up, rotation: float, mirrored: bool = False) -> np.ndarray:
    """The orthogonal matrix (3x3) that places a map in the world: where `mirrored`, its x
    negated (the map as a mirror shows it: u runs the other way about its centre column), then a
    turn of `rotation` degrees about its zenith (+y; R_y, counter-clockwise seen from above),
    then the shortest turn that takes +y to `up`. Every rotation, and every rotation after a
    mirror, is one of these (split_rotation)."""
    a = math.radians(rotation)
    turn = np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0], [-math.sin(a), 0.0, math.cos(a)]])
    if mirrored:
        turn[:, 0] = -turn[:, 0]
    up = np.asarray(up, np.float64)
    return _shortest_turn(up / np.linalg.norm(up)) @ turn


def split_rotation(r: np.ndarray) -> tuple:
    """(up, rotation, mirrored) of an orthogonal r (3x3) as world_from_map takes them: a mirror
    where r's determinant is negative, undone on the map's x; then the shortest turn to r's +y
    undone leaves +y where it was, so what is left is a turn about +y."""
    mirrored = bool(np.linalg.det(r) < 0)
    r = r * [-1.0, 1.0, 1.0] if mirrored else r
    up = r[:, 1] / np.linalg.norm(r[:, 1])
    turn = _shortest_turn(up).T @ r
    return tuple(float(c) for c in up), math.degrees(math.atan2(turn[0, 2], turn[0, 0])) % 360.0, mirrored


def _shortest_turn(up: np.ndarray) -> np.ndarray:
    """The rotation by the least angle that takes +y to the unit vector up (Rodrigues' formula
    about y x up), or for up = -y half a turn about +x. The factor (1 - cos) / sin^2 is written
    1 / (1 + cos) where cos = up.y >= 0 and (1 - up.y) / (x^2 + z^2) below, where 1 + up.y cancels."""
    sin2 = up[0] * up[0] + up[2] * up[2]
    if up[1] < 0 and not sin2 > 0:
        return np.diag([1.0, -1.0, -1.0])
    v = np.array([[0.0, up[0], 0.0], [-up[0], 0.0, -up[2]], [0.0, up[2], 0.0]])    # the cross matrix of y x up
    return np.eye(3) + v + v @ v * (1.0 / (1.0 + up[1]) if up[1] >= 0 else (1.0 - up[1]) / sin2)


@dataclass
class Environment:
    image: np.ndarray          # (H, W, 3) float32 linear RGB radiance
    intensity: float = 1.0
    rotation: float = 0.0      # degrees about the map's zenith, turned first
    source: str = "constant"   # a file path, or "constant"
    resampled: bool = False    # the image is not the file's (a pbrt equal-area map made lat-long)
    rows: str = "centres"      # where a map's rows lie: "centres" or Mitsuba 3's "poles" (row_mapping)
    up: tuple = (0.0, 1.0, 0.0)    # the world direction of the map's zenith (unit)
    mirrored: bool = False     # the map's u runs the other way (turned after the mirror)

    name = "environment"
    formats = {"mitsuba": ("constant", "envmap"), "pbrt": "infinite"}
    doc = ("radiance arriving from infinitely far away: a constant colour, or an HDR map (Mitsuba 3's "
           "constant emitter has radiance, its envmap filename and scale)")
    parameters = (
        Parameter("color", "color", 1.0, spectrum="illuminant", mitsuba="radiance", pbrt="L",
                  doc="its radiance, where it has no map"),
        Parameter("map", "string", optional=True, mitsuba="filename", pbrt="filename",
                  doc="an HDR latitude-longitude map (pbrt-v4's: an equal-area square), relative to the "
                      "scene file (TOML: or a map of assets/envmaps)"),
        Parameter("intensity", "number", 1.0, low=0, mitsuba="scale", pbrt="scale", doc="a factor on it"),
        Parameter("rotation", "number", 0.0, doc="degrees about the map's zenith (Mitsuba 3's to_world and pbrt-v4's "
                                                  "CTM place the map)"),
        Parameter("up", "vector", (0.0, 1.0, 0.0), doc="the world direction the map's zenith (its top row) takes: "
                                                       "[0, 0, 1] for a z-up scene's sky"),
        Parameter("mirrored", "bool", False, doc="the map as a mirror shows it, its left and right swapped before it "
                                                 "is turned (Mitsuba 3's to_world that mirrors)"),
        Parameter("rows", "name", "centres", choices=("centres", "poles"), mitsuba_default="poles",
                  doc="a map's rows: each the band of 180 / H degrees about its centre, or, as Mitsuba 3's "
                      "envmap reads them, the first and last centred on the poles, 180 / (H - 1) degrees apart"),
        Parameter(None, "number", pbrt="illuminance", pbrt_default=-1.0,
                  doc="where positive, the illuminance it gives an upward surface (pbrt-v4's Light::Create)"))
    mitsuba_plugins = {"constant": ("color",), "envmap": ("map", "intensity", "rows")}     # which each emitter has

    def __repr__(self) -> str:
        from pathtrace.scene.named import vector
        h, w, _ = self.image.shape
        what = f"constant {vector(self.image[0, 0])}" if (h, w) == (1, 1) else f"{self.source} ({w}x{h})"
        up = "" if tuple(self.up) == (0.0, 1.0, 0.0) else f", up {vector(self.up)}"
        return (f"<Environment {what}, intensity {self.intensity:g}, rotation {self.rotation:g}{up}"
                + (", mirrored" if self.mirrored else "") + ">")

    def map_from_world(self) -> np.ndarray:
        """The rotation (3x3) from world directions to the map's own, in which the kernels map a
        direction to the map (kernels/environment.cl): the inverse of world_from_map(up, rotation,
        mirrored), its transpose."""
        return world_from_map(self.up, self.rotation, self.mirrored).T

    def row_mapping(self) -> tuple:
        """(scale, offset): the map's row, in texels, at v = acos(y) / pi is v * scale + offset
        (kernels/environment.cl), clamped to the first and last rows. "centres": row r covers v in
        [r, r + 1] / H, its centre at (r + 1/2) / H, as pbrt-v4's lat-long lookups and pathtrace's
        own maps; "poles": Mitsuba 3's envmap, row r at v = r / (H - 1), the first at the zenith
        and the last at the nadir (src/emitters/envmap.cpp, eval_spectrum: uv * (res - 1), its
        sampling's sin(y pi / (H - 1)) likewise)."""
        h = self.image.shape[0]
        return (h - 1.0, 0.0) if self.rows == "poles" and h > 1 else (float(h), -0.5)

    @classmethod
    def constant(cls, color, intensity=1.0):
        image = np.broadcast_to(np.asarray(color, np.float32), 3).reshape(1, 1, 3)
        return cls(image=image, intensity=intensity, source="constant")

    @classmethod
    def from_file(cls, path: Path, intensity=1.0, rotation=0.0, where="environment.map", rows="centres",
                  up=(0.0, 1.0, 0.0), mirrored=False):
        from pathtrace.io.images import read_hdr
        return cls(read_hdr(path, where), intensity, rotation, str(path), rows=rows, up=up, mirrored=mirrored)

    @classmethod
    def from_values(cls, values: dict, find, where: str):
        """pathtrace's [environment] of the values its declared names give (a map found by
        find(name), or a colour), its rotation wrapped into [0, 360) (in float64). Raises
        ValueError."""
        if "map" in values and "color" in values:
            raise ValueError("give either 'color' or 'map', not both")
        intensity, rotation = values.get("intensity", 1.0), values.get("rotation", 0.0) % 360.0
        up = np.asarray(values.get("up", (0.0, 1.0, 0.0)), np.float64)
        if not np.linalg.norm(up) > 0:
            raise ValueError("up: must not be zero")
        up, mirrored = tuple(float(c) for c in up / np.linalg.norm(up)), values.get("mirrored", False)
        if "map" in values:
            return cls.from_file(find(values["map"]), intensity, rotation, f"{where}.map", values.get("rows", "centres"),
                                 up, mirrored)
        return cls(cls.constant(values.get("color", 1.0)).image, intensity, rotation, up=up, mirrored=mirrored)

    @classmethod
    def from_mitsuba(cls, kind: str, values: dict, to_world, folder: Path, where: str, warn):
        """Mitsuba 3's `constant` or `envmap` emitter of the values its declared names give
        (mitsuba_plugins), its map turned by to_world() (read where there is a map). Raises ValueError("<Mitsuba name>: <problem>")."""
        if kind == "constant":
            return cls.constant(values.get("color", 1.0))
        if "map" not in values:
            raise ValueError("filename: an envmap needs one")
        if values.get("intensity", 1.0) < 0:
            raise ValueError("scale: must not be negative")
        up, rotation, mirrored = cls.mitsuba_orientation(to_world(), where, warn)
        return cls.from_file(folder / values["map"], values.get("intensity", 1.0), rotation, where,
                             values.get("rows", "poles"), up, mirrored)

    @staticmethod
    def mitsuba_orientation(to_world: np.ndarray, where: str, warn) -> tuple:
        """pathtrace's (up, rotation, mirrored) for a Mitsuba envmap's to_world: Mitsuba maps the
        direction to_world's inverse gives (src/emitters/envmap.cpp) and puts the map's u = 0 at -z
        where pathtrace puts u = 1/2, so the map's placement is to_world times half a turn about +y.
        A to_world that scales or shears is taken by its orthogonal part (its polar decomposition:
        a rotation, or one after a mirror), with a warning; a singular one is left out, with a
        warning."""
        r = to_world[:3, :3]
        u, sigma, vt = np.linalg.svd(r)
        if not sigma[-1] > 1e-9 * sigma[0]:
            warn(f"{where}: to_world is singular; pathtrace leaves it out")
            return (0.0, 1.0, 0.0), 180.0, False
        if not np.allclose(sigma, sigma[0], rtol=1e-6):
            warn(f"{where}: to_world scales or shears the map; pathtrace takes its rotation alone")
        return split_rotation(u @ vt @ np.diag([-1.0, 1.0, -1.0]))

    @classmethod
    def from_pbrt(cls, values: dict, given: dict, resolve, inverse, where: str):
        """pbrt-v4's `infinite` light of the values its declared names give (`given`: by pbrt's
        names): its equal-area square map made latitude-longitude through inverse() (the CTM's
        inverse; resolve(name) finds the file), or L; both times scale and, where
        `illuminance` is positive, as pbrt-v4's Light::Create scales them: a constant L by
        E_v / pi, a map by E_v over its upper_illuminance. Raises ValueError("<pbrt name>: <problem>")."""
        from pathtrace.scene.pbrt.equal_area import to_latlong, upper_illuminance
        scale, illuminance = values.get("intensity", 1.0), given["illuminance"]
        if "map" in values:
            if "color" in values:
                raise ValueError("L: an infinite light takes L or a filename, not both")
            from pathtrace.io.images import read_hdr
            path = resolve(values["map"])
            image = read_hdr(path, f"{where}: filename")
            if image.shape[0] != image.shape[1]:
                raise ValueError(f"{path}: pbrt-v4's environment maps are square (equal-area), "
                                 f"got {image.shape[1]}x{image.shape[0]}")
            if illuminance > 0:
                upper = upper_illuminance(image)
                if upper <= 0:
                    raise ValueError("illuminance: the map is black above its horizon, which no scale brightens")
                scale *= illuminance / upper
            latlong = to_latlong(image[..., :3], inverse()[:3, :3])
            return cls(latlong, scale, 0.0, str(path), resampled=True)
        color = np.broadcast_to(values.get("color", 1.0), 3) * scale
        if np.any(color < 0):
            raise ValueError(f"{'scale' if scale < 0 else 'L'}: must not be negative")
        return cls.constant(color * illuminance / math.pi if illuminance > 0 else color)

    def sampling_cdfs(self):
        """The piecewise-constant distribution kernels/environment.cl samples: luminance times
        sin(theta) per texel; a marginal CDF over rows (H + 1 values) and a conditional CDF per
        row (H x (W + 1)). A constant environment needs none (it is sampled by cosine)."""
        h, w, _ = self.image.shape
        if h == 1 and w == 1:
            return np.zeros(2, np.float32), np.zeros(2, np.float32)
        theta = (np.arange(h) + 0.5) / h * np.pi
        # the luminance in the texels' float32, summed in float64, in place: a 2048 x 1024 map's
        # tables in 0.02 s where mixed types and temporaries took 0.07 s of a warm start
        weight = (self.image @ LUMINANCE.astype(self.image.dtype)).astype(np.float64)
        weight *= np.sin(theta)[:, None]
        np.maximum(weight, 0.0, out=weight)
        weight += 1e-12                               # no zero rows
        rows = np.cumsum(weight, axis=1, out=weight)
        row_sum = rows[:, -1].copy()
        conditional = np.empty((h, w + 1), np.float32)
        conditional[:, 0] = 0.0
        conditional[:, 1:] = np.divide(rows, row_sum[:, None], out=rows)
        conditional[:, -1] = 1.0
        marginal = np.zeros(h + 1)
        marginal[1:] = np.cumsum(row_sum) / row_sum.sum()
        marginal[-1] = 1.0
        return marginal.astype(np.float32), conditional

    def rgba(self) -> np.ndarray:
        """The map as float4 texels, the layout the kernel reads."""
        h, w, _ = self.image.shape
        out = np.zeros((h, w, 4), np.float32)
        out[..., :3] = self.image
        return out
