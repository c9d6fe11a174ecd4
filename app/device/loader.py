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

`render` and `view` start the drivers once NumPy is imported, before pyopencl and the rest of
the package (start_drivers_early, from the console's entry point), through the loader that
pyopencl's wheel carries, found by its path: on the H200 machine those imports and the drivers'
start had come one after the other. Begun before NumPy's import, the drivers' loading delayed
it, and a mesh scene's warm start lost what a built-in scene's gained
(docs/notes/performance-2026-12.md, twenty-second session). This module imports pyopencl only
in the functions that need it."""

import ctypes
import ctypes.util
import functools
import importlib.util
import os
import threading
from pathlib import Path

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
        return _declared(ctypes.CDLL(cl._cl.__file__))
    except (OSError, AttributeError):
        return None


def _declared(lib):
    """lib, the three functions' arguments declared."""
    lib.clGetPlatformIDs.argtypes = [ctypes.c_uint32, ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint32)]
    lib.clGetDeviceIDs.argtypes = [ctypes.c_void_p, ctypes.c_uint64, ctypes.c_uint32, ctypes.c_void_p,
                                   ctypes.POINTER(ctypes.c_uint32)]
    lib.clCreateContext.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.POINTER(ctypes.c_void_p),
                                    ctypes.c_void_p, ctypes.c_void_p, ctypes.POINTER(ctypes.c_int32)]
    lib.clCreateContext.restype = ctypes.c_void_p
    return lib


def start_drivers():
    """Lists every platform's devices through the loader, which starts their drivers, so that
    pyopencl's listing after it is quick. Once, the callers after the first waiting for it: the
    loader's first call is not safe beside another thread's (pyopencl's calls, holding the GIL,
    were never made at once); a start under way in start_drivers_early's thread is waited for."""
    global _started
    with _first_call:
        if not _started:
            _list_through(opencl_library())
            _started = True


def start_drivers_early():
    """start_drivers' listing begun in a thread of its own before pyopencl is imported, through
    the loader beside pyopencl (_loader_beside_pyopencl). Not a daemon: a command that ends
    before it (a bad scene file) waits for it, rather than tear the drivers down as they start."""
    def listing():
        with _first_call:
            path = _loader_beside_pyopencl()
            try:
                _list_through(_declared(ctypes.CDLL(path)) if path else None)
            except (OSError, AttributeError):
                pass
    threading.Thread(target=listing, name="start-drivers").start()


def _loader_beside_pyopencl():
    """The OpenCL loader that pyopencl's extension links, found without importing pyopencl: the
    one its wheel carries (auditwheel puts it in pyopencl/.libs, or in pyopencl.libs beside it),
    else the system's. Where they differ, the vendors' drivers, each loaded once per process,
    still start here."""
    spec = importlib.util.find_spec("pyopencl")
    if spec is not None and spec.origin:
        package = os.path.dirname(os.path.abspath(spec.origin))
        carried = sorted([*Path(package).glob(".libs/libOpenCL*.so*"),
                          *Path(package).parent.glob("pyopencl.libs/libOpenCL*.so*")])
        if carried:
            # the carried loader finds the wheel's own drivers by this, and crashes without it;
            # pyopencl's import sets it so
            os.environ["PYOPENCL_HOME"] = package
            return str(carried[0])
    return ctypes.util.find_library("OpenCL")


def _list_through(lib):
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
