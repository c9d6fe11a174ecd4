"""Caustic photons (kernels/photons.cl) on the host: a photon pass before each BDPT sample, one
light subpath per pixel into a hashed grid on the device, and the radius it is gathered within,
which shrinks from pass to pass so that the estimate's bias vanishes (Knaus and Zwicker,
"Progressive photon mapping: a probabilistic approach", ACM TOG 30(3), 2011). A part of the
Renderer (app/rendering/renderer.py), which is one."""

import math

import numpy as np
import pyopencl as cl

from pathtrace.device.types import PHOTON, PHOTON_MAP

ALPHA = 2.0 / 3.0      # Knaus and Zwicker's alpha, the share of its variance each pass keeps: 2/3,
                       # as they and pbrt-v4's SPPM (its gamma) take it
PHOTON_BUFFERS = ("photons", "photon_next", "photon_heads", "photon_count")


def photon_radius(first: float, sample: int) -> float:
    """The gather radius of the pass before sample number `sample` (0 first): r_1 = `first`, then
    r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1) (Knaus and Zwicker's eq. 18), as a product in closed
    form, so that a sample has its radius whichever device or farm actor draws it."""
    return first * math.exp(0.5 * (math.lgamma(sample + 1 + ALPHA) - math.lgamma(1 + ALPHA) - math.lgamma(sample + 2)))


class PhotonPasses:
    """The Renderer's photon passes (BDPT with settings.photon_radius)."""

    _photons_for = None       # (resets, sample) of the photon map in the buffers, and the
    _photon_args = None       # render_bdpt arguments that gather it

    def uses_photons(self, integrator: str = None) -> bool:
        """Whether rendering with `integrator` (by default the settings') traces caustic photons."""
        return (integrator or self.settings.integrator) == "bdpt" and self.settings.photon_radius > 0

    def _photon_pass(self, launch, whole: tuple, local: tuple) -> tuple:
        """Queues the photon pass of launch `launch` (one sample): the lists' heads cleared, then
        trace_photons over the whole image. Returns its events and the arguments by which
        render_bdpt gathers them. A sample drawn in bands of rows (the viewer's launches, several
        devices) traces its photons once: the map stays until the next sample or reset."""
        key = (self.resets, int(launch["sample_start"]))
        if key == self._photons_for:
            return [], self._photon_args
        paths = self.width * self.height
        lists = 1 << (paths - 1).bit_length()        # a power of two, at least one list per photon
        b, queue = self._buffers, self.backend.queue
        if "photons" not in b:
            sizes = {"photons": PHOTON.itemsize * paths, "photon_next": 4 * paths, "photon_heads": 4 * lists,
                     "photon_count": 4}
            for name, size in sizes.items():
                b[name] = cl.Buffer(self.backend.context, cl.mem_flags.READ_WRITE, size)
        photon_map = np.zeros((), PHOTON_MAP)
        photon_map["radius"] = photon_radius(self.settings.photon_radius, int(launch["sample_start"]))
        photon_map["paths"], photon_map["mask"] = paths, lists - 1
        events = [cl.enqueue_fill_buffer(queue, b["photon_heads"], np.int32(-1), 0, 4 * lists),
                  cl.enqueue_fill_buffer(queue, b["photon_count"], np.int32(0), 0, 4)]
        self.photon_kernel.set_args(*self.scene_args(), launch, *(b[name] for name in PHOTON_BUFFERS), photon_map)
        events.append(cl.enqueue_nd_range_kernel(queue, self.photon_kernel, whole, local))
        self._photons_for, self._photon_args = key, (b["photons"], b["photon_next"], b["photon_heads"], photon_map)
        return events, self._photon_args
