"""Cameras: a Camera (camera.py: the frame every projection shares) and one module per
projection, each a dataclass of its own fields beside its kernel file kernels/cameras/<name>.cl,
found by registry.py. Each type's class is exported here under its class name."""

from pathtrace.cameras.camera import MAX_EXTENT, Camera
from pathtrace.cameras.registry import CAMERAS, KERNELS, kernel_parts

globals().update({cls.__name__: cls for cls in CAMERAS.values()})

__all__ = ["CAMERAS", "Camera", "KERNELS", "MAX_EXTENT", "kernel_parts",
           *(cls.__name__ for cls in CAMERAS.values())]
