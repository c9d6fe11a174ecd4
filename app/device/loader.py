"""The two slow calls of opening a device, made through the OpenCL loader with Python's GIL
released, so that a command reads and compiles its scene while they run.

pyopencl holds the GIL in clGetPlatformIDs, where the OpenCL loader starts every vendor's driver,
and in clCreateContext, where NVIDIA's driver makes a CUDA context: on an H200 (driver 580) they
took 0.15 s and 0.13 s, during which no other Python thread ran, so the scene's reading "beside"
the device's opening waited for them (docs/notes/performance-2026-11.md, 2026-11-30, fifteenth
session). ctypes releases the GIL for the length of a foreign call. The functions are the loader's
that pyopencl's extension is linked against (its wheel carries one); the vendors' drivers are
loaded once per process, so a platform listed here is listed by pyopencl at once after. Where
the functions cannot be found or a call fails, pyopencl makes the call itself: these are only
faster.

`render` and `view` start the drivers in a thread once NumPy is imported, beside the rest of the
package's imports (start_drivers_early, from the console's entry point): on the H200 machine
those imports and the drivers' start had come one after the other (docs/notes/performance-2026-12.md,
twenty-second session). So this module imports pyopencl only in the functions that need it."""

import ctypes
import functools
import threading

ALL_DEVICE_TYPES = 0xFFFFFFFF
_first_call = threading.Lock()
_started = False


@functools.cache
def opencl_library():
    """The loader's functions as pyopencl's extension resolves them (the dynamic linker looks
    them up through its dependencies, which name the loader it was built with), or None where
    they cannot be found so (Windows' lookup searches the extension alone)."""
    import pyopencl as cl
    try:
        lib = ctypes.CDLL(cl._cl.__file__)
        lib.clGetPlatformIDs.argtypes = [ctypes.c_uint32, ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint32)]
        lib.clGetDeviceIDs.argtypes = [ctypes.c_void_p, ctypes.c_uint64, ctypes.c_uint32, ctypes.c_void_p,
                                       ctypes.POINTER(ctypes.c_uint32)]
        lib.clCreateContext.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.POINTER(ctypes.c_void_p),
                                        ctypes.c_void_p, ctypes.c_void_p, ctypes.POINTER(ctypes.c_int32)]
        lib.clCreateContext.restype = ctypes.c_void_p
        return lib
    except (OSError, AttributeError):
        return None


def start_drivers():
    """Lists every platform's devices through the loader, which starts their drivers, so that
    pyopencl's listing after it is quick. Once, the callers after the first waiting for it: the
    loader's first call is not safe beside another thread's (pyopencl's calls, holding the GIL,
    were never made at once)."""
    global _started
    with _first_call:
        if not _started:
            _list_through_loader()
            _started = True


def start_drivers_early() -> threading.Thread:
    """start_drivers in a thread of its own, which imports pyopencl first, and the thread:
    `render` and `view` call it once NumPy is imported, so that pyopencl's import and the
    drivers' start run beside the rest of the package's imports. The console leaves past the
    interpreter's teardown while it runs (pathtrace.cli.console); not a daemon, so that a
    teardown that comes anyway waits for it rather than unload the drivers as they start. What
    fails here (no pyopencl) is said by the device's opening after."""
    def start():
        try:
            start_drivers()
        except Exception:
            pass
    thread = threading.Thread(target=start, name="start-drivers")
    thread.start()
    return thread


def _list_through_loader():
    lib = opencl_library()
    if lib is None:
        return
    count = ctypes.c_uint32()
    if lib.clGetPlatformIDs(0, None, ctypes.byref(count)) != 0 or not count.value:
        return
    platforms = (ctypes.c_void_p * count.value)()
    if lib.clGetPlatformIDs(count.value, platforms, None) != 0:
        return
    for platform in platforms:
        found = ctypes.c_uint32()
        lib.clGetDeviceIDs(platform, ALL_DEVICE_TYPES, 0, None, ctypes.byref(found))


def new_context(device):
    """A context of the one device (a pyopencl Device), made by the loader and held by pyopencl."""
    import pyopencl as cl
    lib = opencl_library()
    if lib is not None:
        error = ctypes.c_int32()
        handle = lib.clCreateContext(None, 1, (ctypes.c_void_p * 1)(device.int_ptr), None, None, ctypes.byref(error))
        if handle and error.value == 0:
            return cl.Context.from_int_ptr(handle, retain=False)
    return cl.Context([device])
