"""The caches that PyOpenCL and PoCL keep of their own, made usable before either loads. PyOpenCL
keeps generated code in pytools' cache folder and fails with a traceback where that folder cannot
be made (a read-only home, XDG_CACHE_HOME on a read-only disk); PoCL lists no device at all where
it cannot write its kernel cache. Where such a folder cannot be written, PyOpenCL's cache is
turned off (PYOPENCL_NO_CACHE) and PoCL is given a temporary folder (POCL_CACHE_DIR), removed at
the exit: a start with no writable cache still renders (#55), compiling what a cache would have
held. pathtrace's own caches refuse an unwritable folder by themselves (app/io/cache_files.py)."""

import os
import sys

_temporary = None       # the temporary folder given to PoCL, if any


def writable(folder: str) -> bool:
    """Whether `folder` is a folder this process writes in, made where it is not there yet (as
    its library would make it at its first use): a permission check alone passes a root process
    on a file system that refuses it."""
    try:
        os.makedirs(folder, exist_ok=True)
    except (OSError, ValueError):
        return False
    return os.access(folder, os.W_OK | os.X_OK)


def _user_cache(name: str) -> str:
    """Where platformdirs (which pytools asks) and PoCL put a cache called `name` on Linux:
    under XDG_CACHE_HOME, else ~/.cache; elsewhere platformdirs' own answer."""
    if not sys.platform.startswith("linux"):
        import platformdirs
        return platformdirs.user_cache_dir(name, name)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, name)


def make_usable():
    """Turns PyOpenCL's cache off and gives PoCL a temporary one where their folders cannot be
    written; what the user set is left as it is. Before PyOpenCL is imported and the drivers
    start (pathtrace's import calls it)."""
    if "PYOPENCL_NO_CACHE" not in os.environ and "pyopencl" not in sys.modules \
            and not writable(_user_cache("pytools")):
        os.environ["PYOPENCL_NO_CACHE"] = "1"
    global _temporary
    if "POCL_CACHE_DIR" not in os.environ and not writable(_user_cache("pocl")):
        import atexit
        import tempfile
        try:
            _temporary = tempfile.mkdtemp(prefix="pathtrace-pocl-")
        except OSError:         # nowhere to write: PoCL says it has no device, and pathtrace says how to get one
            return
        os.environ["POCL_CACHE_DIR"] = _temporary
        atexit.register(remove_temporary)


def remove_temporary():
    """Removes the temporary folder given to PoCL, if any: at the interpreter's exit, and before
    a command leaves past it (app/cli/console.py)."""
    if _temporary is not None:
        import shutil
        shutil.rmtree(_temporary, ignore_errors=True)
