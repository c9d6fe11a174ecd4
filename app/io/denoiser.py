"""Denoising with Intel Open Image Denoise (OIDN), through pyoidn, whose wheel bundles OIDN with
its CPU device and its CUDA one. The "RT" filter (a U-Net trained on path-traced images) takes
the noisy HDR radiance with the first non-specular surface's albedo and normal
(kernels/aovs.cl) as guides, which keep texture and geometric edges sharp.

A Denoiser owns one OIDN device and filter and reuses them, since creating a filter costs more
than running it. OIDN runs outside the GIL (pyoidn calls it through cffi), so a window can
denoise in a worker thread and stay smooth. A Denoiser is not for two threads at once: its
device buffers are shared by every call."""

import numpy as np

QUALITIES = ("high", "balanced", "fast")   # OIDN's quality presets: slower is sharper
BORDER = 16                                # pixels mirrored about each edge (Denoiser.__call__)


def _oidn():
    """pyoidn, or one line saying how to get it."""
    try:
        import pyoidn
    except ImportError as e:          # an install without it (it is a dependency)
        from pathtrace.errors import UserError
        raise UserError(f"denoising needs pyoidn (pip install pyoidn): {e}") from None
    return pyoidn


def _finite_nonnegative(image: np.ndarray) -> np.ndarray:
    """OIDN's HDR input must be finite and non-negative."""
    return np.ascontiguousarray(np.nan_to_num(np.maximum(image, 0.0), posinf=65504.0), np.float32)


class Denoiser:
    def __init__(self, quality="high"):
        """quality: one of QUALITIES, or a function of the device's name ("CUDA" or "CPU") that
        gives one. The device is OIDN's CUDA one where a CUDA GPU is present, else its CPU one."""
        oidn = _oidn()
        self._oidn = oidn
        gpu = oidn.Device.is_cuda_available()
        self.device_name = "CUDA" if gpu else "CPU"
        if callable(quality):
            quality = quality(self.device_name)
        self._device = oidn.Device(oidn.OIDN_DEVICE_TYPE_CUDA if gpu else oidn.OIDN_DEVICE_TYPE_CPU)
        self._device.commit()
        self._check("creating the device")
        self._filter = oidn.Filter(self._device, oidn.OIDN_FILTER_TYPE_RT)
        self._filter.set_bool("hdr", True)
        self._filter.set_quality({"high": oidn.OIDN_QUALITY_HIGH, "balanced": oidn.OIDN_QUALITY_BALANCED,
                                  "fast": oidn.OIDN_QUALITY_FAST}[quality])
        self._bound = None          # (height, width, guides) of the buffers bound to the filter
        self._buffers = {}

    def close(self):
        """Releases OIDN's buffers, filter and device (pyoidn frees nothing by itself)."""
        for buffer in self._buffers.values():
            buffer.release()
        self._buffers = {}
        self._filter.release()
        self._device.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _check(self, what: str):
        """OIDN's last error as one line (a user's render must not end in a traceback)."""
        error = self._device.get_error()
        if error:
            from pathtrace.errors import UserError
            raise UserError(f"Open Image Denoise, {what}: {error}")

    def _bind(self, height: int, width: int, guides: tuple):
        """Device buffers for the colour, the output and the `guides` given ("albedo", "normal"),
        bound to the filter, the guides not given unset (again when the size or the guides
        change: the old buffers are released, or every size change kept four images' worth, 14
        MB a camera move in the viewer, whose draft and full sizes alternate)."""
        if self._bound == (height, width, guides):
            return
        self._bound = None              # until the filter takes the new ones (a failure leaves none bound)
        oidn, nbytes = self._oidn, height * width * 12
        names = (oidn.OIDN_IMAGE_COLOR, *guides, oidn.OIDN_IMAGE_OUTPUT)
        old, self._buffers = self._buffers, {name: oidn.Buffer(self._device, nbytes) for name in names}
        for name, buffer in self._buffers.items():
            self._filter.set_image(name, buffer, oidn.OIDN_FORMAT_FLOAT3, width, height)
        for name in (oidn.OIDN_IMAGE_ALBEDO, oidn.OIDN_IMAGE_NORMAL):
            if name not in guides:
                self._filter.unset_image(name)
        for buffer in old.values():      # the filter now holds the new ones
            buffer.release()
        self._filter.commit()
        self._check("preparing the filter")
        self._bound = (height, width, guides)

    def prepare(self, height: int, width: int):
        """Runs once on black images of this size, with both guides: OIDN's first run at a size is
        slower."""
        black = np.zeros((height, width, 3), np.float32)
        self(black, black, black)

    def __call__(self, color: np.ndarray, albedo: np.ndarray = None, normal: np.ndarray = None) -> np.ndarray:
        """The denoised (H, W, 3) float32 radiance, from the noisy radiance and the guides given:
        the albedo in [0, 1], and with it the normal (each (H, W, 3)). The images are denoised
        with BORDER pixels mirrored about each edge, cut off again after: OIDN alone moved a flat
        grey image's pixels near the edges by up to 78 % (docs/notes/performance-2026-12.md,
        2026-12-03)."""
        oidn = self._oidn
        given = {oidn.OIDN_IMAGE_ALBEDO: albedo, oidn.OIDN_IMAGE_NORMAL: normal}
        guides = tuple(name for name, image in given.items() if image is not None)
        h, w, _ = color.shape
        height, width = h + 2 * BORDER, w + 2 * BORDER
        self._bind(height, width, guides)
        nbytes = height * width * 12
        images = [(oidn.OIDN_IMAGE_COLOR, _finite_nonnegative(color))] + [(name, given[name]) for name in guides]
        for name, image in images:
            edges = ((BORDER, BORDER), (BORDER, BORDER), (0, 0))
            self._buffers[name].write(0, nbytes, np.pad(np.asarray(image, np.float32), edges, mode="reflect"))
        self._filter.execute()
        self._check("denoising")
        out = np.empty((height, width, 3), np.float32)
        self._buffers[oidn.OIDN_IMAGE_OUTPUT].read(0, nbytes, out)
        return out[BORDER:BORDER + h, BORDER:BORDER + w].copy()
