"""The camera: eye, look-at point and up vector, and a projection, each a kernel file
kernels/cameras/<name>.cl (kernels/camera.cl is their interface): "perspective", a pinhole or,
with an aperture, a thin lens (kernels/cameras/thinlens.cl); or "orthographic"."""

import math
from dataclasses import dataclass, field

import numpy as np

from pathtrace.device.features import GENERIC, choice_glue

PROJECTIONS = ("perspective", "orthographic")
CAMERA_KERNELS = ("perspective", "thinlens", "orthographic")   # kernel_name's; RenderParams.camera_type
MAX_EXTENT = 1e30     # the largest aperture, focus distance or view height a file may give


def _normalize(v):
    return v / np.linalg.norm(v)


@dataclass
class Camera:
    eye: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 5.0]))
    look_at: np.ndarray = field(default_factory=lambda: np.zeros(3))
    up: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    vfov: float = 45.0                 # perspective: the vertical field of view, degrees
    projection: str = "perspective"    # one of PROJECTIONS
    aperture: float = 0.0              # perspective: the lens's radius (0: a pinhole)
    focus_distance: float = 1.0        # perspective with an aperture: the distance along the
                                       # view direction to the plane in focus
    height: float = 2.0                # orthographic: the view's height in world units
    mirrored: bool = False             # the image's right is -(forward x up): a left-handed
                                       # camera, as pbrt's LookAt gives (app/scene/pbrt)

    def __post_init__(self):
        self.eye = np.asarray(self.eye, np.float64)
        self.look_at = np.asarray(self.look_at, np.float64)
        self.up = np.asarray(self.up, np.float64)

    def __repr__(self) -> str:
        from pathtrace.scene.named import vector
        lens = (f", vfov {self.vfov:g}" + (f", aperture {self.aperture:g} focused at {self.focus_distance:g}"
                                          if self.aperture > 0 else "")) if self.projection != "orthographic" \
            else f", height {self.height:g}"
        return (f"<Camera {self.projection} at {vector(self.eye)} looking at {vector(self.look_at)}, up "
                f"{vector(self.up)}{lens}{', mirrored' if self.mirrored else ''}>")

    def check(self):
        """Raises ValueError("<field>: <problem>") for the first field out of range (the view
        itself, eye, look_at and up, the readers check)."""
        if self.projection not in PROJECTIONS:
            raise ValueError(f"type: must be perspective, thinlens or orthographic, got {self.projection!r}")
        if not 0 < self.vfov < 180:
            raise ValueError(f"vfov: must be between 0 and 180 degrees, got {self.vfov:g}")
        for name in ("aperture", "focus_distance", "height"):
            value = getattr(self, name)
            if not (0 <= value <= MAX_EXTENT if name == "aperture" else 0 < value <= MAX_EXTENT):
                raise ValueError(f"{name}: must be {'in [0' if name == 'aperture' else 'in (0'}, "
                                 f"{MAX_EXTENT:g}], got {value:g}")

    def basis(self, aspect: float):
        """Unit forward, and right and up scaled so that the image spans forward + x right + y up
        (perspective) or eye + x right + y up (orthographic), x and y in [-1, 1]
        (kernels/cameras/)."""
        forward = _normalize(self.look_at - self.eye)
        right = _normalize(np.cross(forward, self.up))
        up = np.cross(right, forward)
        if self.mirrored:
            right = -right
        half_height = self.height / 2 if self.projection == "orthographic" else math.tan(math.radians(self.vfov) / 2)
        return forward, right * half_height * aspect, up * half_height

    def ray(self, aspect: float, x: float, y: float):
        """The ray through the image's point (x, y) in [-1, 1]^2, +y up, from the lens's centre:
        (origin, unit direction)."""
        forward, right, up = self.basis(aspect)
        if self.projection == "orthographic":
            return self.eye + x * right + y * up, forward
        return self.eye, _normalize(forward + x * right + y * up)

    def copy(self) -> "Camera":
        return Camera(self.eye.copy(), self.look_at.copy(), self.up.copy(), self.vfov, self.projection,
                      self.aperture, self.focus_distance, self.height, self.mirrored)


def kernel_name(camera: Camera) -> str:
    """The kernel file (kernels/cameras/<name>.cl) of a camera: a perspective camera with an
    aperture has one of its own, "thinlens", so that pinholes compile none of the lens."""
    return "thinlens" if camera.projection == "perspective" and camera.aperture > 0 else camera.projection


def kernel_parts(projection: str) -> list:
    """(name, source) of the camera kernels of a program: the kernel file `projection` (a
    kernel_name, or GENERIC: every one of CAMERA_KERNELS) and the generate_ray that calls it
    (kernels/camera.cl)."""
    names = CAMERA_KERNELS if projection == GENERIC else (projection,)
    glue = choice_glue("CameraRay generate_ray(const RenderParams *p, float sx, float sy, float2 u)",
                       "generate_{}_ray(p, sx, sy, u)", CAMERA_KERNELS, projection, "camera_type")
    # bidirectional path tracing's join to the lens (a BDPT program is never generic, and its
    # camera a perspective one: app/rendering/bdpt.py)
    glue += "#ifdef BDPT\n" + choice_glue("int sample_importance(const RenderParams *p, float3 x, float2 u, CameraImportance *ci)",
                                          "sample_{}_importance(p, x, u, ci)", CAMERA_KERNELS, projection,
                                          "camera_type") + "#endif\n"
    return [("camera.cl", None), *((f"cameras/{n}.cl", None) for n in names),
            ("app/camera.py: kernel_parts", glue)]
