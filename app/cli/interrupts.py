"""Signals: SIGINT and SIGTERM end a run with one line and leave no half-written file
(install, check_interrupt), and are held off while a command's outputs are written (FinalWrite)."""

import signal
import sys

INTERRUPTED = 130          # the shell's exit status for a run ended by SIGINT (128 + 2)
TERMINATED = 143           # and by SIGTERM (128 + 15)

_interrupted = False       # a SIGINT or SIGTERM arrived
_signal = signal.SIGINT    # which (a KeyboardInterrupt no handler saw counts as SIGINT)


def _interrupt(signum, frame):
    """SIGINT and SIGTERM end a run through KeyboardInterrupt, so that every temporary file is
    removed and nothing half-written is left. The signal is remembered too: raised while Python
    ran a weak reference's callback or a __del__ (a garbage collection between two launches), the
    exception is dropped ("Exception ignored in ...") and a render went on to its end; the
    commands' progress callbacks call check_interrupt after each launch."""
    _remember(signum)
    raise KeyboardInterrupt


def _remember(signum):
    global _interrupted, _signal
    _interrupted, _signal = True, signum


def check_interrupt():
    """Raises the KeyboardInterrupt of a signal that arrived but whose exception was dropped."""
    if _interrupted:
        raise KeyboardInterrupt


def interrupted() -> bool:
    """Whether a SIGINT or SIGTERM has arrived: an error that follows is the interrupt's doing. A
    kernel build under way fails when one arrives (PoCL's compiler, LLVM, removes its temporary
    files on the signal, then hands it on), which is the interrupt, not a device that cannot build."""
    return _interrupted


def interrupted_status() -> int:
    """The exit status of a run a signal ended, 128 + its number as shells report it: INTERRUPTED
    for SIGINT (Ctrl-C), TERMINATED for SIGTERM."""
    return TERMINATED if _signal == signal.SIGTERM else INTERRUPTED


def _unraisable(info, default=sys.unraisablehook):
    """Python's report of an exception it had to drop, silent for the interrupt (remembered by
    _interrupt): its traceback would precede the command's one line."""
    if not (info.exc_type is not None and issubclass(info.exc_type, KeyboardInterrupt)):
        default(info)


def install():
    """Puts the handlers in place (the console entry point does, before anything else is imported)."""
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _interrupt)
    sys.unraisablehook = _unraisable


class FinalWrite:
    """Around the writing of a command's outputs (all or none, app/io/images.py): Ctrl-C and
    SIGTERM wait until it ends, and once the outputs are complete they are ignored, so that a
    signal arriving then cannot turn a finished command into an 'interrupted' exit (130). A
    write that fails restores the handlers, and a signal received meanwhile then interrupts."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __enter__(self):
        # Python's handlers, which run in the main thread whichever thread the signal reached
        # (masking the signal would hold it in this thread only, not in the OpenCL driver's)
        self.received = None
        self.saved = {s: signal.signal(s, self._defer) for s in self.SIGNALS}
        return self

    def _defer(self, signum, frame):
        self.received = signum

    def __exit__(self, kind, *exc):
        if kind is None:                 # complete: a signal now changes nothing
            for s in self.SIGNALS:
                signal.signal(s, signal.SIG_IGN)
            return
        for s, handler in self.saved.items():
            signal.signal(s, handler)
        if self.received is not None and kind is not KeyboardInterrupt:
            _remember(self.received)
            raise KeyboardInterrupt
