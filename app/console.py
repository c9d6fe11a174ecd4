"""The console entry point (`pathtrace`, `python -m pathtrace`). It puts its signal handling in place
before it imports the rest of the package (NumPy, PyOpenCL: about 0.2 s), so that Ctrl-C or
SIGTERM during those imports ends the run with one line, as at any later moment, instead of a
KeyboardInterrupt traceback."""

import os
import signal
import sys

INTERRUPTED = 130          # the shell's exit status for a run ended by SIGINT


def _terminate(signum, frame):
    """SIGTERM ends a run as Ctrl-C does: through KeyboardInterrupt, so that every temporary file
    is removed and nothing half-written is left."""
    raise KeyboardInterrupt


def run():
    """pathtrace.cli.main(), then the exit. After an interrupt it leaves at once (os._exit), past the
    interpreter's teardown: tearing down PoCL while it still winds down an interrupted launch
    aborted the process (std::terminate) now and then; every temporary file is removed by then."""
    signal.signal(signal.SIGTERM, _terminate)
    try:
        from pathtrace.cli import main
        code = main()
    except KeyboardInterrupt:        # main() reports its own; this is one during the imports
        print("pathtrace: interrupted", file=sys.stderr)
        code = INTERRUPTED
    if code == INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    raise SystemExit(code)
