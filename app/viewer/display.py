"""The image on its way to a window, without waiting: a copy to the host of what the window's
shader (shaders/display.frag) needs, radiance in rgb and the count it divides by in a. Two ways,
chosen by where the device's memory is (measured with `pathtrace bench --display`):

- "sums": the float4 accumulation buffer as it is (16 bytes a pixel; rgb / sample count). Where
  the device shares memory with the host (PoCL on the CPU, integrated GPUs) this is one memcpy,
  0.65 ms at 1280x720 on two cores, less than any kernel launch: a kernel writing half floats
  and a mapped buffer cost 1.0 ms there.
- "half": kernels/display.cl writes the mean as half floats (8 bytes a pixel; count 1), half
  the bytes over a discrete GPU's bus.

PyPI's pyopencl has no OpenGL sharing, so the window then uploads the pixels to a texture."""

import numpy as np
import pyopencl as cl

MODES = ("sums", "half")


class Display:
    def __init__(self, backend, mode: str = None):
        """mode: one of MODES (default: "sums" where the device shares memory with the host,
        else "half")."""
        self.backend = backend
        self.mode = mode or ("sums" if backend.device.device.host_unified_memory else "half")
        self._kernel = cl.Kernel(backend.opened.program, "mean_half4")   # the display's or a generic program
        self._size = None
        self._pending = None           # (event, pixels) of the request in flight

    @property
    def busy(self) -> bool:
        return self._pending is not None

    def _allocate(self, width: int, height: int):
        if self._size == (width, height):
            return
        if self.mode == "half":
            self._half = cl.Buffer(self.backend.context, cl.mem_flags.WRITE_ONLY, width * height * 8)
        self._host = np.empty((height, width, 4), np.float16 if self.mode == "half" else np.float32)
        self._size = (width, height)

    def request(self, sums: cl.Buffer, width: int, height: int):
        """Queues the way of `sums` (float4 per pixel: radiance sums and the sample count, as
        Renderer's accumulation buffer) to the host; poll() hands the pixels over. Callers ask
        only when not busy."""
        queue = self.backend.queue
        self._allocate(width, height)
        source = sums
        if self.mode == "half":
            pixels = width * height
            self._kernel(queue, (-(-pixels // 64) * 64,), (64,), sums, np.int32(pixels), self._half)
            source = self._half
        event = cl.enqueue_copy(queue, self._host, source, is_blocking=False)
        queue.flush()
        self._pending = (event, self._host)

    def poll(self, consume) -> bool:
        """If the request in flight has finished, hands its (H, W, 4) pixels (float32 or
        float16: radiance in rgb, to be divided by a; top row first) to consume(pixels), which
        must copy them, and returns True; else returns False at once."""
        if self._pending is None:
            return False
        event, array = self._pending
        if event.command_execution_status != cl.command_execution_status.COMPLETE:
            return False
        self._pending = None
        consume(array)
        return True

    def wait(self, consume):
        """Waits for the request in flight and hands its pixels to consume()."""
        if self._pending is not None:
            self._pending[0].wait()
            self.poll(consume)
