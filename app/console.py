"""The console entry point (`pathtrace`, `python -m pathtrace`). It puts its signal handling in place
before it imports the rest of the package (NumPy, PyOpenCL: about 0.2 s), so that Ctrl-C or
SIGTERM during those imports ends the run with one line, as at any later moment, instead of a
KeyboardInterrupt traceback."""

import os
import signal
import sys

INTERRUPTED = 130          # the shell's exit status for a run ended by SIGINT

_interrupted = False       # a SIGINT or SIGTERM arrived


def _interrupt(signum, frame):
    """SIGINT and SIGTERM end a run through KeyboardInterrupt, so that every temporary file is
    removed and nothing half-written is left. The signal is remembered too: raised while Python
    ran a weak reference's callback or a __del__ (a garbage collection between two launches), the
    exception is dropped ("Exception ignored in ...") and a render went on to its end; the
    commands' progress callbacks call check_interrupt after each launch."""
    global _interrupted
    _interrupted = True
    raise KeyboardInterrupt


def check_interrupt():
    """Raises the KeyboardInterrupt of a signal that arrived but whose exception was dropped."""
    if _interrupted:
        raise KeyboardInterrupt


def _unraisable(info, default=sys.unraisablehook):
    """Python's report of an exception it had to drop, silent for the interrupt (remembered by
    _interrupt): its traceback would precede the command's one line."""
    if not (info.exc_type is not None and issubclass(info.exc_type, KeyboardInterrupt)):
        default(info)


def run():
    """pathtrace.cli.main(), then the exit. After an interrupt, or with a kernel build under way
    (_building), it leaves at once (os._exit), past the interpreter's teardown: tearing down PoCL
    while it still winds down an interrupted launch aborted the process (std::terminate) now and
    then; every temporary file is removed by then."""
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _interrupt)
    sys.unraisablehook = _unraisable
    try:
        from pathtrace.cli import main
        code = main()
    except KeyboardInterrupt:        # main() reports its own; this is one during the imports
        print("pathtrace: interrupted", file=sys.stderr)
        code = INTERRUPTED
    if code == INTERRUPTED or _building():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    raise SystemExit(code)


def _building() -> bool:
    """Whether a scene's program is still being built in the background (pathtrace.device.programs):
    NVIDIA's driver crashed the interpreter's teardown around a build under way (SIGSEGV after a
    render that had written its image), so the command leaves past it, the build dropped."""
    programs = sys.modules.get("pathtrace.device.programs")
    return programs is not None and programs.builds_under_way()
