"""The image on its way to a window: the mean radiance of each pixel as half floats
(kernels/display.cl), 8 bytes a pixel instead of the 16 of the float sums, brought to the host
without waiting. Where the device shares memory with the host (PoCL on the CPU, integrated
GPUs), the kernel writes to host memory that is mapped, with no copy at all; elsewhere it is
copied. PyPI's pyopencl has no OpenGL sharing, so a window then uploads the pixels to a
texture, whose shader applies exposure and the tone curve."""

import numpy as np
import pyopencl as cl


class Display:
    def __init__(self, backend, shared: bool = None):
        """shared: map host memory instead of copying (default: where the device says it
        shares memory with the host)."""
        self.backend = backend
        self.shared = backend.device.device.host_unified_memory if shared is None else shared
        self._kernel = cl.Kernel(backend.program, "mean_half4")
        self._size = None
        self._pending = None           # (event, pixels) of the request in flight

    @property
    def busy(self) -> bool:
        return self._pending is not None

    def _allocate(self, width: int, height: int):
        if self._size == (width, height):
            return
        flags = cl.mem_flags.WRITE_ONLY | (cl.mem_flags.ALLOC_HOST_PTR if self.shared else 0)
        self._out = cl.Buffer(self.backend.context, flags, width * height * 8)
        self._host = None if self.shared else np.empty((height, width, 4), np.float16)
        self._size = (width, height)

    def request(self, sums: cl.Buffer, width: int, height: int):
        """Queues the conversion of `sums` (float4 per pixel: radiance sums and the sample count,
        as Renderer's accumulation buffer) and its way to the host; poll() hands the pixels
        over. A request made while one is in flight replaces nothing: callers ask when not busy."""
        queue = self.backend.queue
        self._allocate(width, height)
        pixels = width * height
        self._kernel(queue, (-(-pixels // 64) * 64,), (64,), sums, np.int32(pixels), self._out)
        if self.shared:
            array, event = cl.enqueue_map_buffer(queue, self._out, cl.map_flags.READ, 0,
                                                 (height, width, 4), np.float16, is_blocking=False)
        else:
            array, event = self._host, cl.enqueue_copy(queue, self._host, self._out, is_blocking=False)
        queue.flush()
        self._pending = (event, array)

    def poll(self, consume) -> bool:
        """If the request in flight has finished, hands its (H, W, 4) float16 pixels (mean
        radiance in rgb, top row first) to consume(pixels), which must copy them (they are
        unmapped after), and returns True; else returns False at once."""
        if self._pending is None:
            return False
        event, array = self._pending
        if event.command_execution_status != cl.command_execution_status.COMPLETE:
            return False
        self._pending = None
        consume(array)
        if self.shared:
            array.base.release(self.backend.queue)
        return True

    def wait(self, consume):
        """Waits for the request in flight and hands its pixels to consume()."""
        if self._pending is not None:
            self._pending[0].wait()
            self.poll(consume)
