"""Running `pathtrace` commands from the tests: in a process of their own (pathtrace), for what only
a process shows, or in the test's process (in_process, as_a_command), which spares a process's
start and imports, about a second of CPU a command (issue #60). tests/test_cli.py
(test_in_process_runs_are_what_the_entry_point_prints) checks that the two print the same."""

import contextlib
import io
import os
import signal
import subprocess
import sys
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def pathtrace(*args, cwd=ROOT, env=None):
    """`python -m pathtrace ARGS`, the real entry point, in a process of its own: for what only a
    process shows (its exit status as the shell sees it, what a driver writes to the standard
    error's file descriptor, signals, what the process imports, the interpreter's exit)."""
    return subprocess.run([sys.executable, "-m", "pathtrace", *map(str, args)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


def in_process(*args, cwd=ROOT):
    """The command run by pathtrace.cli.main.main in this process (as_a_command), as the result
    of `pathtrace`: the status is main()'s, or that of the SystemExit argparse raises. An
    exception that escapes main() (a traceback in a process) fails the test that ran it."""
    from pathtrace.cli.main import main
    with as_a_command(cwd) as (out, err):
        try:
            code = main([str(a) for a in args])
        except SystemExit as e:
            code = 0 if e.code is None else e.code
    return subprocess.CompletedProcess(["pathtrace", *map(str, args)], code, out.getvalue(), err.getvalue())


@contextlib.contextmanager
def as_a_command(cwd, keep_devices: bool = False):
    """Around a command run in this process, from the folder `cwd`: its standard output and
    error captured (yielded, as two StringIO), Python's warnings printed there, each once, where
    a process prints most of them and pytest would keep them, and what a command may change of
    the process put back afterwards: the current folder, the environment (--program sets
    PATHTRACE_PROGRAM), the SIGINT and SIGTERM handlers (a finished write ignores both:
    pathtrace.cli.interrupts.FinalWrite), and the devices the API keeps open (a device takes its
    program mode from the environment it was opened in, which a test may have changed: each
    command opens its own, a few tenths of a second, as a process would), unless `keep_devices`
    (tests/fuzz_batch.py: its cases share one process, one environment and the devices)."""
    from pathtrace import api
    out, err = io.StringIO(), io.StringIO()
    folder, environ, backends = os.getcwd(), dict(os.environ), dict(api._backends)
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    os.chdir(cwd)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), warnings.catch_warnings():
            warnings.simplefilter("default")
            yield out, err
    finally:
        os.chdir(folder)
        for s, handler in handlers.items():
            signal.signal(s, handler)
        for name in set(os.environ) - set(environ):
            del os.environ[name]
        os.environ.update(environ)
        if not keep_devices:
            api._backends.clear()        # the devices it opened go with it
            api._backends.update(backends)
