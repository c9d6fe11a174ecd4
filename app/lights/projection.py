"""A projection light (pbrt-v4's `projection`): a point light that projects an image through a
perspective frustum, like a slide projector. In the light's own space (its y turned round, as
pbrt-v4's ProjectionLight::Create flips it), a direction w with w.z above pbrt's hither (1e-3)
meets the screen at s = (w.x, w.y) / (w.z tan(fov / 2)), which spans [-1, 1] on the image's
shorter axis and its aspect ratio on the longer; inside it, the radiant intensity is `scale` times
the image's texel nearest to s (W/sr), and outside none. `power` (pbrt-v4) scales it to that many
watts: the power of scale 1 is A times the image's mean luminance times cos^3 (the solid angle of a
texel), A the screen's area at distance 1 (ProjectionLight's constructor). The light's frame: +z
along `direction`, +y along `up`, +x = y cross z; in a pbrt file, the CTM's. Mitsuba 3 has no such
emitter (TOML and pbrt-v4 only). kernels/lights/projection.cl samples it."""

import math
from dataclasses import dataclass

import numpy as np

from pathtrace.scene.environment import LUMINANCE
from pathtrace.lights.light import PBRT_POWER, DeltaLight, check_point, frame_quaternion, placed_in_frame
from pathtrace.parameters import Parameter
from pathtrace.resources import resource_dir
from pathtrace.device.slots import Slot, write_slot
from pathtrace.textures import TEXTURES, Image, Texture


def screen(image: Image) -> np.ndarray:
    """The screen's half extents (x, y) for an image of its size: 1 on the shorter axis."""
    w, h = image.size
    return np.array([w / h, 1.0]) if w > h else np.array([1.0, h / w])


def unit_power(image: Image, fov: float) -> float:
    """The power of scale 1: A mean(luminance cos^3), the mean over the texels' centres."""
    tan = math.tan(math.radians(fov) / 2)
    half = screen(image)
    w, h = image.size
    sx = ((np.arange(w) + 0.5) / w * 2 - 1) * half[0] * tan
    sy = ((np.arange(h) + 0.5) / h * 2 - 1) * half[1] * tan
    cos3 = (1 + sx[None, :] ** 2 + sy[:, None] ** 2) ** -1.5
    luminance = image.linear_values()[..., :3] @ LUMINANCE
    return 4 * tan * tan * half[0] * half[1] * float(np.mean(luminance * cos3))


def _pbrt_scale(scale, given):
    """pbrt-v4: scale, and where `power` is given, times power over the power of scale 1."""
    if given["power"] > 0:
        return scale * given["power"] / unit_power(given["filename"], given["fov"])
    return scale


@dataclass
class ProjectionLight(DeltaLight):
    position: np.ndarray
    image: Image
    scale: float = 1.0
    fov: float = 90.0
    direction: np.ndarray = (0.0, 0.0, 1.0)
    up: np.ndarray = (0.0, 1.0, 0.0)
    name = "projection"
    formats = {"pbrt": "projection"}
    parameters = (
        *placed_in_frame("its frame's +z, the frustum's axis", "its frame's +y, the image's up"),
        Parameter("image", "image", doc="the image projected (rgb intensities, W/sr, times scale)", pbrt="filename"),
        Parameter("fov", "number", 90.0, low=0.0, high=180.0, doc="the frustum's angle across the image's "
                  "shorter axis, degrees", pbrt="fov", pbrt_default=90.0),
        Parameter("scale", "number", 1.0, low=0.0, doc="a factor on the image", pbrt="scale", pbrt_default=1.0,
                  from_pbrt=_pbrt_scale),
        PBRT_POWER)
    slots = (Slot("position", "p0.xyz", "where it is"), Slot("slide", "p0.w", "the image's row of the texture table"),
             Slot("scale", "p1.x", "the factor on the image"), Slot("tan_half_fov", "p1.y", "tan(fov / 2)"),
             Slot("half_extent", "p1.zw", "the screen's half extents"),
             Slot("rotation", "p2.xyzw", "the rotation from the light's space to the world's, a unit quaternion"))
    examples = ({"position": [0.1, 1.2, -0.1], "direction": [0.2, -1.0, 0.1], "up": [0.0, 0.0, -1.0],
                 "scale": 3.0, "fov": 70.0, "image": str(resource_dir("assets") / "textures" / "tiles.png")},)

    def check(self):
        self.position = check_point("position", self.position)
        self.rotation = frame_quaternion(self.direction, self.up)
        if not isinstance(self.image, Image):
            raise ValueError("image: must be an image")
        if not 0 < self.fov < 180 or not math.isfinite(self.fov):
            raise ValueError(f"fov: must be in (0, 180) degrees, got {self.fov:g}")
        if not 0 <= self.scale < 1e20 or not math.isfinite(self.scale):
            raise ValueError(f"scale: must be in [0, 1e20), got {self.scale:g}")
        self.slide = Texture("bitmap", TEXTURES["bitmap"].complete(
            {"image": self.image, "filter": "nearest", "wrap": "clamp"}))

    def power(self, radius: float) -> float:
        return self.scale * unit_power(self.image, self.fov)

    def textures(self):
        return [self.slide]

    def pack(self, row, texture_rows):
        super().pack(row, texture_rows)
        for name, value in (("slide", texture_rows[id(self.slide)]), ("tan_half_fov", math.tan(math.radians(self.fov) / 2)),
                            ("half_extent", screen(self.image)), ("rotation", self.rotation)):
            write_slot(row, self.slot_of(name), value)

    def tree_bounds(self):
        """Its axis, and every direction out to the screen's corner (pbrt-v4's
        ProjectionLight::Bounds: cos theta_o 1, cos theta_e the corner's)."""
        corner = screen(self.image) * math.tan(math.radians(self.fov) / 2)
        axis = np.asarray(self.direction, np.float64)
        return self.position, axis / np.linalg.norm(axis), 1.0, 1 / math.sqrt(1 + corner @ corner)
