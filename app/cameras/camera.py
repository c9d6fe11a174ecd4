"""The camera interface: what every projection shares, its frame (eye, look_at, up and whether
the image is mirrored, which the viewer's moves and the readers' transforms set), and what each
projection declares in its own module app/cameras/<type>.py beside its kernel file
kernels/cameras/<kernel>.cl: its fields and the formats' parameters that map onto them
(app/parameters.py: their names in pathtrace's TOML, Mitsuba 3 and pbrt-v4, defaults and docs),
their ranges, its rays, its packing into RenderParams and its mapping of a Mitsuba or pbrt
camera's values onto its fields (Camera.from_file; frame_of, the frame of the file's transform).
app/cameras/registry.py finds the modules and generates the kernels' dispatch."""

import dataclasses
import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from pathtrace.errors import UserError, short, with_article
from pathtrace.parameters import Parameter

MAX_EXTENT = 1e30     # the largest aperture, focus distance or view height a file may give
# what a reader adds to a file camera's `given` values (app/parameters.py: read), which the
# mapping onto a type's fields needs: the film's (width, height) and the camera's transform to
# the world (a 4 x 4 matrix: Mitsuba's to_world, the inverse of pbrt's camera CTM)
FILM, TO_WORLD = "film", "to_world"

# pbrt-v4's CameraBase parameters that frame the image (pbrt_screen_half_height), and the lens
# of its perspective and orthographic cameras (src/pbrt/cameras.cpp, the cameras' Create)
PBRT_SCREEN = (Parameter(None, "number", pbrt="frameaspectratio", doc="the screen window's aspect; by default "
                         "the film's"),
               Parameter(None, "numbers", pbrt="screenwindow", doc="x0 x1 y0 y1: the screen space the image "
                         "spans, its height framing the image"))
PBRT_LENS = (Parameter(None, "number", pbrt="lensradius", pbrt_default=0.0, doc="the lens's radius: above 0, a "
                       "perspective camera is a thinlens one, and an orthographic one ignores it, with a warning"),
             Parameter(None, "number", pbrt="focaldistance", pbrt_default=1e6, doc="the thin lens's focus_distance"))


def check_range(name: str, value, low: float, high: float, open_low: bool = False, open_high: bool = False):
    """Raises ValueError("<name>: <problem>") where value is not a number in the range."""
    inside = isinstance(value, (int, float, np.number)) and not isinstance(value, bool) and \
        (low < value if open_low else low <= value) and (value < high if open_high else value <= high)
    if not inside:
        shown = f"{value:g}" if isinstance(value, (int, float, np.number)) else repr(value)
        raise ValueError(f"{name}: must be in {'(' if open_low else '['}{low:g}, {high:g}{')' if open_high else ']'}, "
                         f"got {shown}")


def check_choice(name: str, value, choices: tuple):
    """Raises ValueError("<name>: <problem>") where value is none of `choices`."""
    if value not in choices:
        raise ValueError(f"{name}: must be {', '.join(choices[:-1])} or {choices[-1]}, got {value!r}")


def frame_of(world_from_camera: np.ndarray, x_right: bool) -> dict:
    """A Camera's frame (eye, look_at, up, mirrored) of a file's camera-to-world transform,
    camera space looking down +z with +y up and +x the image's right (pbrt-v4) or left
    (Mitsuba 3): a transform that turns +x the other way mirrors the image."""
    r, eye = world_from_camera[:3, :3], world_from_camera[:3, 3]
    forward, up, x = r @ [0, 0, 1.0], r @ [0, 1.0, 0], r @ [1.0, 0, 0]
    side = np.dot(np.cross(forward, up), x)
    return dict(eye=eye, look_at=eye + forward / np.linalg.norm(forward), up=up,
                mirrored=bool(side < 0 if x_right else side > 0))


def pbrt_screen_half_height(given: dict, warn) -> float:
    """Half the image's height in pbrt's screen space, where the fov spans [-1, 1] (or an
    orthographic camera one world unit each way), of a pbrt camera's `given` values (PBRT_SCREEN
    and FILM): pbrt-v4's CameraBase screen window (src/pbrt/cameras.cpp, CameraBaseParameters /
    the cameras' Create: frame = frameaspectratio, else the film's x / y; the window
    [-frame, frame] x [-1, 1] where frame > 1, else [-1, 1] x [-1/frame, 1/frame]; or the file's
    `screenwindow` x0 x1 y0 y1). pathtrace's image is centred and its pixels square, so the
    window's height frames it; a window off centre or of another aspect than the film's is taken
    so, with a warning (warn(text, the parameter's name)). Raises ValueError("<name>: <problem>")."""
    w, h = given[FILM]
    frame = given["frameaspectratio"]
    frame = w / h if frame is None else frame
    if not frame > 0 or not math.isfinite(frame):
        raise ValueError(f"frameaspectratio: must be positive, got {frame:g}")
    window = (-frame, frame, -1.0, 1.0) if frame > 1 else (-1.0, 1.0, -1 / frame, 1 / frame)
    name = "frameaspectratio"
    if given["screenwindow"] is not None:
        window, name = tuple(float(v) for v in given["screenwindow"]), "screenwindow"
        if len(window) != 4 or not window[0] < window[1] or not window[2] < window[3]:
            raise ValueError("screenwindow: takes x0 x1 y0 y1 with x0 < x1 and y0 < y1")
    x0, x1, y0, y1 = window
    if not math.isclose(x0, -x1, abs_tol=1e-6 * (x1 - x0)) or not math.isclose(y0, -y1, abs_tol=1e-6 * (y1 - y0)):
        warn(f"pathtrace's image is centred on the view; it uses a centred window of the same size, "
             f"[{-(x1 - x0) / 2:g} {(x1 - x0) / 2:g} {-(y1 - y0) / 2:g} {(y1 - y0) / 2:g}]", name)
    if not math.isclose((x1 - x0) / (y1 - y0), w / h, rel_tol=1e-4):
        warn(f"a window of aspect {(x1 - x0) / (y1 - y0):g} on a film of {w / h:g} has pixels that are not "
             "square; pathtrace's are, and it frames the window's height", name)
    return (y1 - y0) / 2


def _normalize(v):
    return v / np.linalg.norm(v)


@dataclass
class Camera:
    """A camera's frame. A projection subclasses it with its own fields (keyword or after up),
    and sets the class attributes below."""
    eye: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 5.0]))
    look_at: np.ndarray = field(default_factory=lambda: np.zeros(3))
    up: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    mirrored: bool = field(default=False, kw_only=True)
    # the image's right is -(forward x up): a left-handed camera, as pbrt's LookAt gives

    type: ClassVar[str] = None           # its name in TOML and the registry
    parameters: ClassVar[tuple] = ()     # its own fields, declared (app/parameters.py: Parameter;
                                         # a name's field holds one of its choices)
    sliders: ClassVar[dict] = {}         # {field: (low, high, logarithmic)}: the viewer panel's
                                         # slider of a number field
    kernels: ClassVar[tuple] = ()        # its kernel files' names (kernels/cameras/<name>.cl;
                                         # default (type,)), which `kernel` chooses among
    importance: ClassVar[bool] = False   # its kernel files define sample_<kernel>_importance, the
                                         # join of a light subpath to its lens (kernels/camera.cl):
                                         # bidirectional path tracing can render through it
    format_only: ClassVar[tuple] = ()    # the formats' parameters that are none of its fields
                                         # (name None), which from_file maps onto them
    mitsuba: ClassVar[str] = None        # the Mitsuba 3 sensor type it reads (from_file)
    pbrt: ClassVar[str] = None           # the pbrt-v4 Camera type it reads (from_file)
    toml_aliases: ClassVar[tuple] = ()   # other TOML types that are this one where a table gives
                                         # its own fields (a perspective camera with a lens)

    def __post_init__(self):
        if self.type is None:
            raise TypeError("Camera is the cameras' base; make one of pathtrace.cameras.CAMERAS' types "
                            "(PerspectiveCamera, ...)")
        self.eye = np.asarray(self.eye, np.float64)
        self.look_at = np.asarray(self.look_at, np.float64)
        self.up = np.asarray(self.up, np.float64)

    def __setattr__(self, name, value):
        # a field of another camera type set on this one would change nothing: say so
        names = [f.name for f in dataclasses.fields(self)]
        if name not in names:
            raise AttributeError(f"{with_article(self.type)} camera has no {name!r} (its fields: {', '.join(names)}; "
                                 "Camera.as_type makes another type)")
        super().__setattr__(name, value)

    def as_type(self, type_name: str, **fields) -> "Camera":
        """A camera of the registered type `type_name` with this one's frame, the fields the two
        types share, and `fields`."""
        if type_name not in Camera.types():
            raise UserError(f"camera.as_type: no camera type {short(type_name)} (types: {', '.join(Camera.types())})")
        cls = Camera.types()[type_name]
        theirs = {f.name for f in dataclasses.fields(cls)}
        shared = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name in theirs}
        return cls(**{**shared, **fields}).copy()

    @staticmethod
    def types() -> dict:
        """Every subclass of Camera with a `type`, defined in this package, by type name in name
        order: the registry's CAMERAS, once it has imported the package's modules (which
        importing any of them does first)."""
        found, todo = {}, list(Camera.__subclasses__())
        while todo:
            cls = todo.pop(0)
            todo += cls.__subclasses__()
            if cls.type is not None and cls.__module__.startswith("pathtrace.cameras."):
                found[cls.type] = cls
        return dict(sorted(found.items()))

    @property
    def kernel(self) -> str:
        """Its kernel file's name (kernels/cameras/<kernel>.cl), RenderParams.camera_type's."""
        return self.type

    def __repr__(self) -> str:
        from pathtrace.scene.named import vector
        own = "".join(f", {p.name} {getattr(self, p.name) if p.choices else format(getattr(self, p.name), 'g')}"
                      for p in self.parameters)
        return (f"<Camera {self.type} at {vector(self.eye)} looking at {vector(self.look_at)}, up "
                f"{vector(self.up)}{own}{', mirrored' if self.mirrored else ''}>")

    def check(self):
        """Raises ValueError("<field>: <problem>") for the first of its own fields out of range
        (the view itself, eye, look_at and up, the readers check); a name must be one of its
        choices. A type checks its numbers' ranges on top of this."""
        for p in self.parameters:
            if p.choices:
                check_choice(p.name, getattr(self, p.name), p.choices)
        return self

    @classmethod
    def from_file(cls, fmt: str, values: dict, given: dict, frame: dict, warn) -> "Camera":
        """The camera, checked, of a Mitsuba 3 or pbrt-v4 camera (fmt "mitsuba", "pbrt") read by
        the type's declarations (app/parameters.py: read, of parameters + format_only): `values`
        by pathtrace's names, `given` by the format's with FILM and TO_WORLD, `frame` frame_of's;
        warn(text, the format's name or None) says what it changes. Raises ValueError("<name>:
        <problem>"), the name pathtrace's or the format's. A type whose fields the format's values
        do not give as they are maps them here, before this."""
        return cls(**frame, **values).check()

    def frame(self):
        """Unit forward, right (the image's) and up."""
        forward = _normalize(self.look_at - self.eye)
        right = _normalize(np.cross(forward, self.up))
        up = np.cross(right, forward)
        return forward, -right if self.mirrored else right, up

    def basis(self, aspect: float):
        """forward, right and up as RenderParams holds them (kernels/cameras/): by default the
        frame with right and up scaled to the image's half width and half height."""
        forward, right, up = self.frame()
        h = self.half_height()
        return forward, right * h * aspect, up * h

    def half_height(self) -> float:
        return 1.0

    def lens(self) -> tuple:
        """RenderParams.lens: what else its kernel reads."""
        return (0.0, 0.0, 0.0, 0.0)

    def pack(self, p, aspect: float):
        """Writes its fields into RenderParams p (app/device/types.py) for an image of `aspect`."""
        p["eye"][:3] = self.eye
        p["forward"][:3], p["right"][:3], p["up"][:3] = self.basis(aspect)
        p["lens"] = self.lens()

    def ray(self, aspect: float, x: float, y: float):
        """The ray through the image's point (x, y) in [-1, 1]^2, +y up, from the lens's centre:
        (origin, unit direction), as its kernel draws it."""
        raise NotImplementedError

    def copy(self):
        return dataclasses.replace(self, eye=self.eye.copy(), look_at=self.look_at.copy(), up=self.up.copy())

    def toml(self) -> dict:
        """Its [camera] table, without the medium."""
        table = {"type": self.type, "eye": self.eye.tolist(), "look_at": self.look_at.tolist(),
                 "up": self.up.tolist()}
        table.update({p.name: getattr(self, p.name) if p.choices else float(getattr(self, p.name))
                      for p in self.parameters})
        return {**table, "mirrored": True} if self.mirrored else table
