"""The driver's start and a device's context made through the OpenCL loader with the GIL released
(app/device/loader.py): the devices and contexts are pyopencl's own, and listing from several
threads at once, the loader's first call among them, finds every device in each."""

import subprocess
import sys

import numpy as np
import pyopencl as cl

from pathtrace.device import loader
from pathtrace.device.opencl import list_devices
from tests.conftest import ROOT


def test_a_context_made_through_the_loader_is_the_devices_and_runs_kernels(backend):
    device = backend.device.device
    context = loader.new_context(device)
    assert loader.opencl_library() is not None and context.devices == [device]
    queue = cl.CommandQueue(context)
    program = cl.Program(context, "__kernel void twice(__global float *a) { a[get_global_id(0)] *= 2.0f; }").build()
    a = np.arange(16, dtype=np.float32)
    buffer = cl.Buffer(context, cl.mem_flags.READ_WRITE | cl.mem_flags.COPY_HOST_PTR, hostbuf=a)
    program.twice(queue, a.shape, None, buffer)
    cl.enqueue_copy(queue, a, buffer)
    assert np.array_equal(a, 2 * np.arange(16))


def test_without_the_loader_pyopencl_makes_the_context(backend, monkeypatch):
    monkeypatch.setattr(loader, "opencl_library", lambda: None)
    assert loader.new_context(backend.device.device).devices == [backend.device.device]


def test_devices_listed_from_several_threads_at_once_in_a_new_process():
    code = ("import threading\n"
            "from pathtrace.device.opencl import list_devices\n"
            "found = []\n"
            "threads = [threading.Thread(target=lambda: found.append(len(list_devices()))) for _ in range(4)]\n"
            "[t.start() for t in threads]; [t.join() for t in threads]\n"
            "print(found)\n")
    expected = len(list_devices())
    for _ in range(3):
        r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
        assert r.returncode == 0 and r.stdout.strip() == str([expected] * 4), (r.stdout, r.stderr[-2000:])


def test_drivers_started_early_in_a_new_process():
    """After start_drivers_early, as `render` and `view` call it, a new process lists every device
    once: the early thread and the device's opening share the loader's first call. (A first form
    listed through the loader of pyopencl's wheel loaded by its path, which kept an empty list
    where the drivers are found through pyopencl's extension alone: tests/test_packaging.py, the
    [cpu] extra's PoCL, renders through the console's entry point.)"""
    code = ("from pathtrace.device import loader\n"
            "loader.start_drivers_early()\n"
            "from pathtrace.device.opencl import list_devices\n"
            "print(len(list_devices()))\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.split() == [str(len(list_devices()))], \
        (r.stdout, r.stderr[-2000:])
