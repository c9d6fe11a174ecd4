"""Shared fixtures: one OpenCL device (PoCL on the CPU in CI) and test kernels built beside the
real ones."""

import os
from pathlib import Path

import numpy as np
import pyopencl as cl
import pytest

from pathtrace.device import choose_device, open_device

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def backend():
    """The device the tests run on: PATHTRACE_TEST_DEVICE, else the first CPU."""
    return choose_device(os.environ.get("PATHTRACE_TEST_DEVICE", "cpu"))


class KernelRunner:
    """Builds the kernels plus a test kernel, and runs it on NumPy arrays."""

    def __init__(self, backend, source):
        self.backend = open_device(backend.device, extra=source)
        self.ctx, self.queue = self.backend.context, self.backend.queue

    def __call__(self, name, global_size, *args):
        bufs, outs = [], []
        for a in args:
            if isinstance(a, np.ndarray) and a.ndim > 0:   # 0-d: a struct passed by value
                flags = cl.mem_flags.READ_WRITE | cl.mem_flags.COPY_HOST_PTR
                buf = cl.Buffer(self.ctx, flags, hostbuf=np.ascontiguousarray(a))
                bufs.append(buf)
                outs.append((buf, a))
            else:
                bufs.append(a)
        kernel = cl.Kernel(self.backend.program, name)
        kernel(self.queue, (global_size,), None, *bufs)
        for buf, a in outs:
            cl.enqueue_copy(self.queue, a, buf)
        self.queue.finish()


@pytest.fixture(scope="session")
def kernels(backend):
    cache = {}

    def make(source):
        if source not in cache:
            cache[source] = KernelRunner(backend, source)
        return cache[source]
    return make


def scene_arrays(compiled):
    """The arrays of a CompiledScene in the order of the kernels' SCENE_KERNEL_ARGS (empty ones
    padded to one element, as the Renderer uploads them)."""
    lights = compiled.lights
    marginal, conditional = compiled.scene.environment.sampling_cdfs()
    arrays = (compiled.bvh.nodes, compiled.spheres, compiled.triangles, compiled.normals,
              compiled.prim_material, compiled.materials, compiled.scene.environment.rgba(),
              lights.lights, lights.pick, marginal, conditional)
    return [np.ascontiguousarray(a) if a.size else np.zeros(1, a.dtype) for a in arrays]
