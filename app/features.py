"""What a scene needs of the kernels: the device-independent key by which app/device.py
specialises the kernel program to a scene."""

from dataclasses import dataclass


@dataclass(frozen=True)
class Features:
    """What a scene needs of the kernels. Each scene's program is specialised to it and leaves
    out the code of the shapes and materials the scene lacks: on a GPU every branch a kernel
    could take costs registers, hence occupancy, in every thread (docs/performance.md).
    The default, everything, is the program that tests and the warm-up build."""
    triangles: bool = True
    bsdfs: tuple = None       # names of app.materials.BSDFS; None: all of them

    def defines(self) -> tuple:
        return () if self.triangles else ("NO_TRIANGLES",)
