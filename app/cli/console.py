"""The console entry point (`pathtrace`, `python -m pathtrace`). It puts its signal handling in place
before it imports the rest of the package (NumPy, PyOpenCL: about 0.2 s), so that Ctrl-C or
SIGTERM during those imports ends the run with one line, as at any later moment, instead of a
KeyboardInterrupt traceback. NumPy loads with one BLAS thread (_numpy_on_one_blas_thread); then
`render` and `view` start the OpenCL drivers while the rest is imported
(pathtrace.device.loader: start_drivers_early)."""

import os
import sys

from pathtrace.cli.interrupts import INTERRUPTED, TERMINATED, install, interrupted_status
from pathtrace.device import driver_caches

OPENBLAS_THREADS = "OPENBLAS_NUM_THREADS"


def run():
    """pathtrace.cli.main.main(), then the exit. After an interrupt, with a kernel build under way
    (_building), or with the drivers still starting in their early thread (a command that ended
    before it needed them: help, an option refused, no display), it leaves at once (os._exit),
    past the interpreter's teardown: tearing down PoCL while it still winds down an interrupted
    launch aborted the process (std::terminate) now and then; every temporary file is removed by
    then, and the cache entries being written are written first unless the run was interrupted."""
    install()
    drivers = None
    try:
        _numpy_on_one_blas_thread()
        if sys.argv[1:2] in (["render"], ["view"]):     # the commands that open a device at once
            from pathtrace.device.loader import start_drivers_early
            drivers = start_drivers_early()
        from pathtrace.cli.main import main
        code = main()
    except KeyboardInterrupt:        # main() reports its own; this is one during the imports
        print("pathtrace: interrupted", file=sys.stderr)
        code = interrupted_status()
    except SystemExit as e:          # argparse's, after its help or its one line
        if drivers is None or not drivers.is_alive():
            raise
        code = e.code if isinstance(e.code, int) else 0 if e.code is None else 1
    stopped = code in (INTERRUPTED, TERMINATED)
    if stopped or _building() or drivers is not None and drivers.is_alive():
        sys.stdout.flush()
        sys.stderr.flush()
        if not stopped:
            _finish_cache_writes()
        driver_caches.remove_temporary()
        os._exit(code)
    raise SystemExit(code)


def _numpy_on_one_blas_thread():
    """Imports NumPy with OPENBLAS_NUM_THREADS=1 unless the user set it, and takes the variable back
    out, so that the programs a command starts (Mitsuba in `bench`) see the user's environment.
    OpenBLAS starts a thread per core when it loads, each spinning for a while before it sleeps;
    pathtrace calls BLAS on 3x3 and 4x4 matrices alone, and on the H200 machine's 16 cores those
    spinning threads slowed the device's opening beside the scene's reading by half a second
    (docs/notes/performance-2026-12.md, twenty-second session)."""
    if OPENBLAS_THREADS in os.environ:
        import numpy    # noqa: F401
        return
    os.environ[OPENBLAS_THREADS] = "1"
    try:
        import numpy    # noqa: F401
    finally:
        del os.environ[OPENBLAS_THREADS]


def _finish_cache_writes():
    """Waits for the caches' writes under way (pathtrace.io.cache_files.write_soon: the geometry
    cache's, the meshes kept beside the scene cache's entries), which a leaving past the
    interpreter's teardown would cut short. An interrupt ends the wait: the user asked to stop,
    and a write's temporary file left then is removed by a later write's prune."""
    wait = getattr(sys.modules.get("pathtrace.io.cache_files"), "wait_for_writes", None)
    try:
        if wait is not None:
            wait()
    except KeyboardInterrupt:
        pass


def _building() -> bool:
    """Whether a scene's program is still being built in the background (pathtrace.device.programs),
    or the BVH builder's kernels (pathtrace.compiler.builder, built after a device's opening, or
    compiled ahead on PoCL in a build thread): NVIDIA's
    driver crashed the interpreter's teardown around a build under way (SIGSEGV after a render that
    had written its image), and the interpreter would wait for the builder's thread, so the command
    leaves past it, the build dropped. A module another thread is still importing has neither."""
    checks = (getattr(sys.modules.get("pathtrace.device.programs"), "builds_under_way", None),
              getattr(sys.modules.get("pathtrace.compiler.builder"), "building", None))
    return any(check is not None and check() for check in checks)
