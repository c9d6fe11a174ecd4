"""A goniometric light (pbrt-v4's `goniometric`): a point light whose radiant intensity in
direction w is `intensity` times an image of directions, I(w) = intensity image(s(w')), where w'
is w in the light's own space with its y and z swapped (pbrt-v4's GoniometricLight::Create turns
the light's frame so, making its +y the map's pole) and s is Clarberg's equal-area mapping of the
sphere onto the square (pbrt-v4's EqualAreaSphereToSquare; app/scene/pbrt/equal_area.py), the
image looked up at the nearest texel. As pbrt-v4, the image is square and its channels are
averaged into one (pbrt's "Y" channel); `power` scales the light to that many watts, k_e being
4 pi times the image's mean. The light's frame: +z along `direction`, +y along `up` (the
map's pole), +x = y cross z; in a pbrt file, the CTM's. Mitsuba 3 has no such emitter (TOML and
pbrt-v4 only). kernels/lights/goniometric.cl samples it."""

import math
from dataclasses import dataclass

import numpy as np

from pathtrace.lights.light import (PBRT_POWER, PBRT_SCALE, DeltaLight, check_color, check_point, frame_quaternion,
                                    luminance, pbrt_scaled, placed_in_frame)
from pathtrace.parameters import Parameter
from pathtrace.resources import resource_dir
from pathtrace.device.slots import Slot, write_slot
from pathtrace.textures import TEXTURES, Image, Texture


def grey(image: Image) -> Image:
    """The image's channels averaged into one, linear (pbrt-v4's GoniometricLight::Create)."""
    values = image.linear_values()[..., :3]
    return Image(np.ascontiguousarray(values.mean(axis=-1)[..., None], np.float32), True, image.path)


@dataclass
class GoniometricLight(DeltaLight):
    position: np.ndarray
    intensity: np.ndarray
    image: Image
    direction: np.ndarray = (0.0, 0.0, 1.0)
    up: np.ndarray = (0.0, 1.0, 0.0)
    name = "goniometric"
    formats = {"pbrt": "goniometric"}
    parameters = (
        *placed_in_frame("its frame's +z", "its frame's +y, the map's pole"),
        Parameter("intensity", "color", doc="radiant intensity where the image is 1, W/sr", spectrum="illuminant",
                  pbrt="I", pbrt_default=1.0,
                  from_pbrt=pbrt_scaled(lambda given: 4 * math.pi * float(np.mean(grey(given["filename"]).texels)))),
        Parameter("image", "image", doc="a square equal-area map of directions (its channels' mean)",
                  pbrt="filename"),
        PBRT_SCALE, PBRT_POWER)
    slots = (Slot("position", "p0.xyz", "where it is"), Slot("map", "p0.w", "the image's row of the texture table"),
             Slot("intensity", "p1.xyz", "radiant intensity I where the image is 1"),
             Slot("rotation", "p2.xyzw", "the rotation from the light's space to the world's, a unit quaternion"))
    examples = ({"position": [0.1, 1.2, -0.2], "intensity": [3.0, 2.0, 1.0], "up": [0.3, -1.0, 0.2],
                 "image": str(resource_dir("assets") / "textures" / "tiles.png")},)

    def check(self):
        self.position = check_point("position", self.position)
        self.intensity = check_color("intensity", self.intensity)
        self.rotation = frame_quaternion(self.direction, self.up)
        if not isinstance(self.image, Image):
            raise ValueError("image: must be an image")
        w, h = self.image.size
        if w != h:
            raise ValueError(f"image: an equal-area map is square, got {w}x{h}")
        self.map = Texture("bitmap", TEXTURES["bitmap"].complete(
            {"image": grey(self.image), "filter": "nearest", "wrap": "clamp"}))

    def power(self, radius: float) -> float:
        """4 pi times the mean intensity: the map is equal-area, so its mean is over the sphere."""
        return 4 * math.pi * float(np.mean(self.map.params["image"].texels)) * luminance(self.intensity)

    def textures(self):
        return [self.map]

    def pack(self, row, texture_rows):
        super().pack(row, texture_rows)
        write_slot(row, self.slot_of("map"), texture_rows[id(self.map)])
        write_slot(row, self.slot_of("rotation"), self.rotation)

    def tree_bounds(self):
        """Bounded as an isotropic point light (pbrt-v4's GoniometricLight::Bounds)."""
        return self.position, np.array([0.0, 0.0, 1.0]), -1.0, 0.0
