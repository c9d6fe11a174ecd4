"""The interactive viewer: a GLFW window (window.py), the image's way to it (display.py, drawn by
a moderngl shader), fly controls and an imgui panel. Nothing in the core imports this package:
only api.view(), the `view` command and `bench --display` do."""

import importlib.util
import os
import sys


def _name_the_bundled_glfw():
    """pyGLFW, imported without PYGLFW_LIBRARY, loads each libglfw it finds in a Python subprocess
    of its own to read its version: 0.04-0.05 s of every window's start on two cores (its import
    0.10 s, 0.057 s with the library named). On Linux its wheel carries the library, for X11 and
    for Wayland, and pyGLFW takes the one of the session's display server; that one is named to
    it here (PYGLFW_LIBRARY and PYGLFW_LIBRARY_VARIANT are pyGLFW's documented settings). A
    user's own setting is kept, and nothing is named where the wheel has no library or where
    LD_LIBRARY_PATH offers one of the user's, which pyGLFW would weigh by its version."""
    spec = importlib.util.find_spec("glfw")
    if not sys.platform.startswith("linux") or os.environ.get("PYGLFW_LIBRARY") or spec is None \
            or not spec.submodule_search_locations or _offered_by_ld_library_path():
        return
    variant = os.environ.get("PYGLFW_LIBRARY_VARIANT", "").lower()
    if variant not in ("wayland", "x11"):
        variant = "wayland" if os.environ.get("XDG_SESSION_TYPE") == "wayland" else "x11"
    library = os.path.join(spec.submodule_search_locations[0], variant, "libglfw.so")
    if os.path.isfile(library):
        os.environ["PYGLFW_LIBRARY"] = library


def _offered_by_ld_library_path() -> bool:
    for folder in filter(None, os.environ.get("LD_LIBRARY_PATH", "").split(":")):
        try:
            if any(name.startswith("libglfw") for name in os.listdir(folder)):
                return True
        except OSError:
            continue
    return False


_name_the_bundled_glfw()
