"""pathtrace: an interactive, progressive path tracer with OpenCL kernels.

The Python API (docs/python.md): load(), load_dict(), material(), render(), progressive(),
denoise(), tonemap(), write(), show(), view() and devices(). Importing pathtrace imports
nothing else: NumPy and PyOpenCL load with the first function used, and the viewer's GL and GUI
packages only with view(). It makes PyOpenCL's and PoCL's own caches usable where their folders
cannot be written (pathtrace.device.driver_caches)."""

from pathtrace.device.driver_caches import make_usable

__version__ = "0.1.0"

make_usable()       # PyOpenCL's and PoCL's caches, where they cannot be written

# name -> the module that defines it, imported on first use (PEP 562)
_EXPORTS = {
    **{name: "pathtrace.api" for name in ("load", "load_dict", "material", "render", "progressive", "denoise",
                                          "tonemap", "write", "show", "view", "devices", "queue_plans",
                                          "programs_used", "Snapshot", "AOVS")},
    "Scene": "pathtrace.scene.description",
    "RenderSettings": "pathtrace.scene.description",
    "PATH_QUEUE_AUTO": "pathtrace.rendering.choices",
    "Camera": "pathtrace.cameras",
    "Environment": "pathtrace.scene.environment",
    "Material": "pathtrace.materials.table",
    "UserError": "pathtrace.errors",
}

# the subpackages that docs/python.md names as pathtrace's attributes (pathtrace.cameras.CAMERAS),
# imported on first use too
_SUBPACKAGES = ("cameras", "lights", "filters", "shapes", "materials", "textures", "scene")

__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name not in _EXPORTS and name not in _SUBPACKAGES:
        raise AttributeError(f"module 'pathtrace' has no attribute {name!r}")
    import importlib
    if name in _SUBPACKAGES:
        return importlib.import_module(f"pathtrace.{name}")     # which sets it in globals()
    value = getattr(importlib.import_module(_EXPORTS[name]), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS) | set(_SUBPACKAGES))
