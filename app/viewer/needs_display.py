"""What the viewer needs of the machine before anything else: a display, found and opened, or
one line saying how to go on without one (a headless render, or a virtual display)."""

import os
import sys

from pathtrace.errors import UserError


def no_display_message(scene: str = "simple") -> str:
    """What to do without a display, with commands that paste as they are: this very program
    (the virtual environment is rarely on PATH) on the scene asked for, and xvfb-run, or how to
    install it."""
    import shlex
    import shutil
    program = shlex.quote(sys.argv[0]) if os.path.basename(sys.argv[0]) == "pathtrace" \
        else f"{shlex.quote(sys.executable)} -m pathtrace"
    named = shlex.quote(scene)
    xvfb = f'xvfb-run -s "-screen 0 1280x800x24" {program} view' + (f" {named}" if scene != "simple" else "")
    if not shutil.which("xvfb-run"):
        xvfb = f"sudo apt install xvfb, then {xvfb}"
    return (f"pathtrace view needs a display, and none was found. To render headless: "
            f"{program} render {named} -o out.png --spp 16 (a first look in seconds; without --spp, the "
            f"scene's own samples). To run the viewer on a virtual display: {xvfb}")


def require_display(scene: str = "simple"):
    """On Linux a window needs an X11 or Wayland display: one that is named and that GLFW opens
    (a DISPLAY of a server that is gone is named but does not open); else one line naming
    `scene`, not a traceback, nor pyGLFW's warning of GLFW's error before it."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise UserError(no_display_message(scene))
    import glfw
    reporting, glfw.ERROR_REPORTING = glfw.ERROR_REPORTING, "ignore"
    try:
        opened = glfw.init()
    finally:
        glfw.ERROR_REPORTING = reporting
    if not opened:
        raise UserError(no_display_message(scene))
