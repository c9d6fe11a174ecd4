"""The programs a device renders with: a generic program that renders any scene (two: with
media and null surfaces, and without, for the scenes that have neither), and each scene's own
program, specialised to its features (app/device/features.py), built in the background.

A specialised program is the fastest a scene can have (on a GPU every branch a kernel could take
costs registers, hence occupancy), but building it can take seconds on a GPU's driver, longer
with the register-cap trials of app/device/occupancy.py, and every new mix of materials, textures and
lights is a new program. The generic programs (Features.generic_program) are built once per
device, driver and pathtrace version and cached (app/device/opencl.py: open_device builds the one
without media where it renders from a cache, `pathtrace devices --check` both everywhere), so that a scene's first images need no build:
they come from the generic program while the scene's own builds in a thread (the drivers'
builds release Python's lock), started once the first pass is queued so that it takes no core
from the first image (Renderer.switch_when_built), and launches switch to it once it is there. Where the generic
program is not built, the first image waits for one untuned build of the scene's own, and the
tuned one (app/device/occupancy.py) follows in the background. Nothing else builds behind a first
image (but the AOVs' small program where a render asks for the AOVs: Renderer.aux_kernel):
NVIDIA's driver takes minutes over the generic program on an H200, and a scene's build in
another thread waited for it (docs/notes/performance-2026-11.md, 2026-11-28).

Both programs draw the same estimator, each sample an unbiased estimate of the pixel, so the
average goes on across the switch (Renderer keeps its accumulation). Which samples a render
draws then depends on when the build ended: PROGRAM_MODES says how to ask for repeatable
renders."""

import atexit
import os
import threading
from concurrent.futures import Future

# No PyOpenCL here: the programs are the builder's (pathtrace.device.opencl), named in annotations
# only, so that the command line reads PROGRAM_MODES and PROGRAM_ENV without loading it (issue #60)
from pathtrace.errors import UserError, warn
from pathtrace.device.features import Features

PROGRAM_MODES = ("auto", "specialised", "generic")
"""auto: the generic program until the scene's own is built (in the background); specialised:
wait for the scene's own program (repeatable renders; the tests marked `specialised`); generic:
never build another for the path tracer (BDPT and light tracing, which no generic program holds,
build their own; repeatable too, the tests' default; the generic program's speed, measured by
`pathtrace bench`)."""
PROGRAM_ENV = "PATHTRACE_PROGRAM"    # the mode where no --program is given
BUILD_THREAD = "pathtrace-build"


def builds_under_way() -> bool:
    """Whether a program is being built in the background in this process (or waits to be), or
    kernels are being compiled ahead of their launches (pathtrace.compiler.builder: Builder.compile_ahead;
    ProgramChoice.compile_ahead)."""
    return any(t.name == BUILD_THREAD and t.is_alive() for t in threading.enumerate())


def in_build_thread(work, then=None):
    """Runs work() in a build thread, whose failure the launch or build that needs its result
    says (a program's build in the background, Programs.start, or what compiles ahead of a
    launch: pathtrace.compiler.builder, Builder.compile_ahead; ProgramChoice.compile_ahead), then
    then(), where given, either way. A daemon thread: a process that ends before the work does
    neither waits for it nor leaves a torn cache entry (app/io/cache_files.py writes whole
    files)."""
    def run():
        try:
            work()
        except Exception:
            pass
        finally:
            if then is not None:
                then()
    threading.Thread(target=run, name=BUILD_THREAD, daemon=True).start()


@atexit.register
def _finish_builds():
    """A script or notebook that ends while a program builds waits for the build (which its
    cache then keeps): the interpreter's teardown under a build in NVIDIA's driver crashed the
    process. The commands leave without waiting (pathtrace.cli.console)."""
    for thread in threading.enumerate():
        if thread.name == BUILD_THREAD:
            thread.join()


def default_mode() -> str:
    mode = os.environ.get(PROGRAM_ENV) or "auto"      # empty: unset
    if mode not in PROGRAM_MODES:
        raise UserError(f"{PROGRAM_ENV}: must be one of {', '.join(PROGRAM_MODES)}, got {mode!r}")
    return mode


class Programs:
    """Programs of one device, each built once, now or in a background thread, on request.
    `build(features, tune)` builds one (pathtrace.device.opencl.build_program, bound to the device);
    `tunes`: whether a tuned build differs from an untuned one (NVIDIA: app/device/occupancy.py)."""

    def __init__(self, build, name: str, tunes: bool):
        self._build = build
        self._name = name
        self._tunes = tunes
        self._lock = threading.Lock()
        self._futures: dict[tuple, Future] = {}
        self._reported = set()

    def _key(self, features: Features, tuned: bool) -> tuple:
        return features, tuned and self._tunes

    def add(self, features: Features, tuned: bool, program: "pyopencl.Program"):
        """A program built elsewhere."""
        future = Future()
        future.set_result(program)
        with self._lock:
            self._futures[self._key(features, tuned)] = future

    def get(self, features: Features, tuned: bool = True) -> "pyopencl.Program":
        """The program for `features`, built now if no build of it is under way or done."""
        return self._future(self._key(features, tuned)).result()

    def start(self, features: Features, tuned: bool = True, after=None):
        """Starts the build of the program for `features` in the background, unless it is built
        or under way; its thread calls after() first, where given (a wait for what should be
        compiled before it)."""
        self._future(self._key(features, tuned), background=True, after=after)

    def ready(self, features: Features, tuned: bool = True):
        """The program for `features` if it is built, else None, its build started in the
        background. A build that failed leaves None and says why once."""
        key = self._key(features, tuned)
        future = self._future(key, background=True)
        if not future.done():
            return None
        error = future.exception()
        if error is None:
            return future.result()
        if key not in self._reported:
            self._reported.add(key)
            warn(f"{self._name}: the {'generic' if features.generic else 'scene' + chr(39) + 's own'} kernels "
                 f"did not build ({str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__})"
                 + ("" if features.generic else "; rendering on with the kernels in use"))
        return None

    def built(self, features: Features, tuned: bool = True):
        """The program for `features` if it is built, else None; starts nothing."""
        future = self._futures.get(self._key(features, tuned))
        return future.result() if future is not None and future.done() and future.exception() is None else None

    def under_way(self, features: Features, tuned: bool = True) -> bool:
        """Whether the program for `features` is being built."""
        future = self._futures.get(self._key(features, tuned))
        return future is not None and not future.done()

    def failed(self, features: Features, tuned: bool = True) -> bool:
        """Whether the build of the program for `features` ended in an error."""
        future = self._futures.get(self._key(features, tuned))
        return future is not None and future.done() and future.exception() is not None

    def _future(self, key: tuple, background: bool = False, after=None) -> Future:
        with self._lock:
            future = self._futures.get(key)
            if future is not None:
                return future
            future = self._futures[key] = Future()
            future.set_running_or_notify_cancel()
        if background:
            in_build_thread(lambda: self._run(key, future, after))
        else:
            self._run(key, future)
            future.result()
        return future

    def _run(self, key: tuple, future: Future, after=None):
        if after is not None:
            try:
                after()
            except Exception:       # a wait that failed holds the build back no longer
                pass
        try:
            future.set_result(self._build(*key))
        except Exception as e:
            future.set_exception(e)

