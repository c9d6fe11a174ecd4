"""The registry of camera types: every module of this package that defines a Camera subclass
with a `type` is one, found by import (so adding a camera takes its module, its kernel file
kernels/cameras/<kernel>.cl and its test, nothing else), and the kernels' generate_ray (and,
for bidirectional path tracing, sample_importance) dispatch generated from it."""

import importlib
import pkgutil
from pathlib import Path

from pathtrace.cameras.camera import Camera
from pathtrace.device.features import GENERIC, choice_glue


def _discover() -> dict:
    for module in sorted(m.name for m in pkgutil.iter_modules([str(Path(__file__).parent)])):
        importlib.import_module(f"pathtrace.cameras.{module}")
    return Camera.types()


CAMERAS = _discover()
"""type name -> Camera subclass, in name order."""

FIELDS = tuple(p for cls in CAMERAS.values() for p in cls.parameters)
"""Every type's fields' declarations, by which a reader names in its own terms the field of a
type's ValueError (the type it read may have made another: pbrt's perspective, a thin lens)."""

KERNELS = tuple(dict.fromkeys(k for cls in CAMERAS.values() for k in (cls.kernels or (cls.type,))))
"""Every camera kernel file's name; RenderParams.camera_type is an index into it."""


def toml_class(kind: str, keys) -> type:
    """The camera type of a TOML [camera] table of type `kind` giving `keys`: the type of that
    name, or a type that takes that name as an alias (ThinLensCamera: a perspective camera with
    a lens) where the table gives one of its own fields; None: no such type."""
    if not isinstance(kind, str):
        return None
    cls = CAMERAS.get(kind)
    for other in CAMERAS.values():
        own = {p.name for p in other.parameters} - {p.name for p in (cls.parameters if cls else ())}
        if kind in other.toml_aliases and own & set(keys):
            return other
    return cls


def format_class(fmt: str, kind: str):
    """The camera type that reads a `fmt` ("mitsuba" or "pbrt") camera of type `kind`, the one
    of that name first where several map to it (pbrt's perspective: PerspectiveCamera, which
    makes a ThinLensCamera where there is a lens); None: none."""
    found = [cls for cls in CAMERAS.values() if getattr(cls, fmt) == kind]
    return min(found, key=lambda cls: cls.type != kind, default=None)


def toml_names() -> list:
    """The types a TOML [camera] table may give."""
    return sorted({*CAMERAS, *(a for cls in CAMERAS.values() for a in cls.toml_aliases)})


def kernel_parts(kernel: str) -> list:
    """(name, source) of the camera kernels of a program: the interface (kernels/camera.cl), the
    kernel file `kernel` (GENERIC: every one of KERNELS) and the generate_ray that calls it; with
    BDPT, the sample_importance of a camera that has one (a BDPT program is never generic, and
    app/rendering/bdpt.py refuses a camera without one)."""
    names = KERNELS if kernel == GENERIC else (kernel,)
    glue = choice_glue("CameraRay generate_ray(const RenderParams *p, float sx, float sy, float2 u)",
                       "generate_{}_ray(p, sx, sy, u)", KERNELS, kernel, "camera_type")
    if kernel != GENERIC and supports_importance(kernel):
        glue += ("#ifdef BDPT\n" + choice_glue("int sample_importance(const RenderParams *p, float3 x, float2 u, "
                                               "CameraImportance *ci)", "sample_{}_importance(p, x, u, ci)",
                                               KERNELS, kernel, "camera_type") + "#endif\n")
    return [("camera.cl", None), *((f"cameras/{n}.cl", None) for n in names),
            ("app/cameras/registry.py: kernel_parts", glue)]


def supports_importance(kernel: str) -> bool:
    """Whether the camera kernel file `kernel` joins light subpaths to its lens (BDPT)."""
    return any(cls.importance and kernel in (cls.kernels or (cls.type,)) for cls in CAMERAS.values())

