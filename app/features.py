"""What a scene needs of the kernels: the device-independent key by which app/device.py
specialises the kernel program to a scene."""

from dataclasses import dataclass


@dataclass(frozen=True)
class Features:
    """What a scene and its settings need of the kernels. Each scene's program is specialised
    to it and leaves out the code of the shapes, materials and Russian roulette rule it does
    not use: on a GPU every branch a kernel could take costs registers, hence occupancy, in
    every thread (docs/performance.md). The default, every shape and material, is the program
    the tests build their kernels beside."""
    triangles: bool = True
    bsdfs: tuple = None                    # names of app.materials.BSDFS; None: all of them
    russian_roulette: str = "throughput"   # one of app.scene.description.RUSSIAN_ROULETTE

    def defines(self) -> tuple:
        return ((() if self.triangles else ("NO_TRIANGLES",))
                + (f"RUSSIAN_ROULETTE=RR_{self.russian_roulette.upper()}",))
