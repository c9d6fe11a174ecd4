"""The caches that PyOpenCL and PoCL keep of their own, made usable before either loads. PyOpenCL
keeps generated code in pytools' cache folder and fails with a traceback where that folder cannot
be made (a read-only home, XDG_CACHE_HOME on a read-only disk); PoCL lists no device at all where
it cannot write its kernel cache. Where such a folder cannot be written, PyOpenCL's cache is
turned off (PYOPENCL_NO_CACHE) and PoCL is given a temporary folder (POCL_CACHE_DIR), removed at
the exit: a start with no writable cache still renders (#55), compiling what a cache would have
held. Nothing is made or changed where the folders can be written. pathtrace's own caches refuse
an unwritable folder by themselves (app/io/cache_files.py)."""

import os
import sys

SET_HERE = {}           # the variables make_usable set, and their values
_temporary = None       # the temporary folder given to PoCL, if any


def writable(folder: str) -> bool:
    """Whether `folder` is, or could be made, a folder this process writes in: the nearest of it
    and its parents that exists is a folder with write permission (a read-only disk's is not).
    Nothing is made."""
    path = os.path.abspath(folder)
    while not os.path.lexists(path):
        parent = os.path.dirname(path)
        if parent == path:
            return False
        path = parent
    return os.path.isdir(path) and os.access(path, os.W_OK | os.X_OK)


def pytools_cache() -> str:
    """Where pytools keeps PyOpenCL's cache: platformdirs' user cache folder, which on Linux takes
    XDG_CACHE_HOME only where it is an absolute path, and on macOS XDG_CACHE_HOME where it is set
    (pytools' own exception, pytools/persistent_dict.py)."""
    xdg = os.environ.get("XDG_CACHE_HOME")
    if sys.platform.startswith("linux"):
        base = xdg if xdg and os.path.isabs(xdg) else os.path.join(os.path.expanduser("~"), ".cache")
        return os.path.join(base, "pytools")
    if sys.platform == "darwin" and xdg is not None:
        return os.path.join(xdg, "pytools")
    import platformdirs
    return platformdirs.user_cache_dir("pytools", "pytools")


def pocl_cache() -> str | None:
    """Where PoCL keeps its kernels when POCL_CACHE_DIR is not set (pocl_cache.c,
    pocl_cache_init_topdir): under XDG_CACHE_HOME as given, else $HOME/.cache, else /tmp; on
    Windows under LOCALAPPDATA, else TEMP."""
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or os.environ.get("TEMP")
        return os.path.join(base, "pocl", "kcache") if base else None
    if os.environ.get("XDG_CACHE_HOME"):
        return os.path.join(os.environ["XDG_CACHE_HOME"], "pocl", "kcache")
    if os.environ.get("HOME") is not None:
        return os.path.join(os.environ["HOME"], ".cache", "pocl", "kcache")
    return "/tmp/pocl/kcache"


def make_usable():
    """Turns PyOpenCL's cache off and gives PoCL a temporary one where their folders cannot be
    written; what the user set is left as it is. Before PyOpenCL is imported and the drivers
    start (pathtrace's import calls it)."""
    global _temporary
    if "PYOPENCL_NO_CACHE" not in os.environ and "pyopencl" not in sys.modules and not writable(pytools_cache()):
        os.environ["PYOPENCL_NO_CACHE"] = SET_HERE["PYOPENCL_NO_CACHE"] = "1"
    pocl = pocl_cache()
    if "POCL_CACHE_DIR" not in os.environ and pocl is not None and not writable(pocl):
        import atexit
        import tempfile
        try:
            _temporary = tempfile.mkdtemp(prefix="pathtrace-pocl-")
        except OSError:         # nowhere to write: PoCL says it has no device, and pathtrace says how to get one
            return
        os.environ["POCL_CACHE_DIR"] = SET_HERE["POCL_CACHE_DIR"] = _temporary
        atexit.register(remove_temporary)


def for_children(env: dict) -> dict:
    """`env` without the variables make_usable set, for a process whose own caches may be
    writable (bench's renders, each given a cache folder of its own): it decides for itself."""
    return {k: v for k, v in env.items() if SET_HERE.get(k) != v}


def remove_temporary():
    """Removes the temporary folder given to PoCL, if any: at the interpreter's exit, and before
    a command leaves past it (app/cli/console.py)."""
    if _temporary is not None:
        import shutil
        shutil.rmtree(_temporary, ignore_errors=True)
