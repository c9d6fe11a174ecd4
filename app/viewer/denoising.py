"""The viewer's denoising: while the camera rests, the image is read back each time its samples
have doubled and denoised (pathtrace.io.denoiser) in a worker thread, never waited for. A part of
the Viewer (app/viewer/window.py), which is one."""

import time

import numpy as np
import pyopencl as cl

from pathtrace.rendering.renderer import aov_means, per_pixel_mean

DRAFT_SCALE = 2                # the first denoised image after a move: at half the resolution
DENOISE_QUALITY = {"CPU": "fast", "CUDA": "high"}   # OIDN's preset for the viewer, by its device:
                               # on two cores "fast" denoises 1280x720 in 0.35 s, "high" in 0.65 s


class Denoising:
    """The Viewer's denoising (its state is set in Viewer.__init__)."""

    def _denoiser_ready(self) -> bool:
        if self._denoiser is None and self.denoise_error is None:
            try:
                from pathtrace.io.denoiser import Denoiser
                self._denoiser = Denoiser(lambda device: DENOISE_QUALITY[device])
                # OIDN's first run at a size prepares it (a third of a second on two cores):
                # done now, in the worker, it is not waited for when the camera stops
                for scale in (DRAFT_SCALE, 1):
                    self._worker.submit(self._prepare_denoiser, self.size[1] // scale, self.size[0] // scale)
            except Exception as e:     # no pyoidn, or OIDN cannot run here: say so, keep going
                self.denoise_error = f"denoiser unavailable: {e}"
                self.set_message(self.denoise_error, error=True)
        return self._denoiser is not None

    def _advance_denoise(self):
        """One step of denoising, never waiting: read the image back once its passes have doubled
        since the last denoise, hand it to the worker thread when it has arrived, and show
        the result when the worker is done. Results of an image since reset are dropped."""
        r, p = self.renderer, self.progressive
        if self._denoising is not None and self._denoising[0].done():
            future, resets, samples = self._denoising
            self._denoising = None
            try:
                image, seconds = future.result()
            except Exception as e:     # a viewer must outlive any failure of the library
                self.denoise_error = str(e)
                self.set_message(f"denoising failed: {e}", error=True)
                self.denoise = False
                return
            if resets == r.resets:
                self.denoised_at, self.denoise_seconds = (resets, samples), seconds
                self._upload(np.concatenate([image, np.ones_like(image[..., :1])], -1))
                self.clean = True
                self._shown = None            # the noisy image is no longer what is shown
        if self._readback is not None:
            event, arrays, resets, samples = self._readback
            if event.command_execution_status != cl.command_execution_status.COMPLETE:
                return
            self._readback = None
            if resets == r.resets and self._denoising is None:
                future = self._worker.submit(self._denoise_job, *arrays)
                self._denoising = (future, resets, samples)
            return
        if self._denoising is not None or p.passes_done < 1:
            return
        last = self.denoised_at[1] if self.denoised_at and self.denoised_at[0] == r.resets else 0
        if p.passes_done >= 2 * last:
            event, arrays = r.read_async(("sum", "albedo_sum", "normal_sum"))
            self._readback = (event, arrays, r.resets, p.passes_done)

    def _denoise_job(self, sums, albedo_sum, normal_sum):
        """In the worker thread: the means, then OIDN (which runs outside the GIL)."""
        start = time.perf_counter()
        aovs = aov_means(albedo_sum, normal_sum)
        image = self._denoise(per_pixel_mean(sums), aovs["albedo"], aovs["normal"])
        return image, time.perf_counter() - start

    def _prepare_denoiser(self, height: int, width: int):
        with self._denoiser_lock:
            self._denoiser.prepare(height, width)

    def _denoise(self, image, albedo, normal):
        """The denoiser, from the worker or the screenshot thread: its buffers are for one
        thread at a time."""
        with self._denoiser_lock:
            return self._denoiser(image, albedo, normal)
