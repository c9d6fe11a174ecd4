"""The viewer's scenes: opened (read, compiled with the BVH build's progress shown, and given to
the renderer) in a worker thread while the window stays live. A part of the Viewer
(app/viewer/window.py), which is one."""

import sys
import threading
import time
from typing import NamedTuple

from pathtrace.compiler.compiled import compile_before_devices
from pathtrace.errors import UserError
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
from pathtrace.viewer.controls import speed_for


class Work(NamedTuple):
    """Work in a thread of its own: its outcome ("value" or "error") once the thread ends, and
    whether it is to stop at its next step (SceneOpening._abandon)."""
    thread: threading.Thread
    outcome: dict
    started: float
    abandoned: threading.Event


class Abandoned(Exception):
    """The outcome of work abandoned before it ended."""


class SceneOpening:
    """The Viewer's opening of scenes (Viewer._wait draws frames while they open)."""

    def _begin(self, work, text: str):
        """work() started in a worker thread (self._work), the window's status saying `text` until
        the work says what it is doing (self._status); Viewer._wait waits for it."""
        outcome = {}

        def call():
            try:
                outcome["value"] = work()
            except BaseException as e:     # handed to the waiting thread
                outcome["error"] = e
        self._status = (text, None)     # (text, fraction done or None), drawn by Viewer._wait
        self._work = Work(threading.Thread(target=call, name="open", daemon=True), outcome, time.perf_counter(),
                          threading.Event())
        self._work.thread.start()

    def _abandon(self):
        """Work begun before the window failed to open stops at its next step (_go_on): a
        driver's build cannot be stopped halfway, and a process that goes on (a notebook) should
        not have a renderer made behind it. The window's error is said at once, not after it."""
        self._work.abandoned.set()

    def _go_on(self):
        """Between the steps of an opening: ends the work where it was abandoned."""
        if self._work.abandoned.is_set():
            raise Abandoned()

    def _start(self, backend, scene) -> Renderer:
        """In the worker thread: the scene read and the device opened, where they are functions
        that do so (the device opens in a thread of its own: api.DevicesOpening), the scene
        compiled while it opens, then given to a renderer on it."""
        if callable(scene):
            self._status = ("reading the scene", None)
            scene = scene()
        self._go_on()
        compiled = self._compile(scene)
        if callable(backend):
            self._status = ("opening the device", None)
            backend = backend()
        self._go_on()
        self.backend = backend
        return self._open(*compiled)

    def _compile(self, scene) -> tuple:
        """The scene compiled, with its tree where the BVH cache holds it or the host builds it, for
        the path tracer, and the integrator it asks for: a scene that asks for BDPT or light
        tracing shows the path tracer's first images (the same image in expectation) while their
        kernels build, then switches (app/viewer/integrators.py)."""
        integrator = scene.settings.integrator
        scene = scene.with_settings(integrator="path")
        return compile_before_devices(scene, self._build_progress(scene.name)), integrator

    def _open(self, compiled, integrator: str, renderer=None) -> Renderer:
        """In the worker thread: the compiled scene given to `renderer` (or a new one): it checks
        the device's memory, starts the build of the scene's kernels and builds its BVH beside
        it (Renderer.set_scene), the BVH's progress shown and then that the kernels are still
        building."""
        self._status = self._preparing(compiled.scene.name)
        if renderer is None:
            renderer = Renderer(self.backend, compiled, all_kernels=True)
        else:
            had, camera = renderer.compiled, renderer.camera
            try:
                renderer.set_scene(compiled)
            except BaseException:     # its kernels or uploads: the scene it had, seen as it was
                renderer.set_scene(had)
                renderer.set_camera(camera)
                raise
        self.requested_integrator = None if integrator == "path" else integrator
        return renderer

    def load_scene(self, name: str):
        """Opens a scene, at its own size or the one the viewer was given (view --size: a user
        sparing the CPU or the GPU); whatever goes wrong is shown in the panel and printed, and
        the window keeps the scene it had. Call it between turns of the loop (the panel asks
        through requested_scene): it draws frames of its own as it goes."""
        started = time.perf_counter()
        self.selected = None          # the shape picked, of the scene the renderer is about to leave

        def read():
            scene = load_scene(name)
            if self.image_size is None:
                return scene
            return scene.with_settings(width=self.image_size[0], height=self.image_size[1])
        try:
            self._begin(lambda: self._open(*self._compile(read()), self.renderer), f"opening {name}")
            scene = self._wait().scene
            self.renderer.resize(scene.settings.width, scene.settings.height)
        except Exception as e:   # a viewer must outlive any bad file, ours or a library's error
            self.set_message(str(e) if isinstance(e, UserError) else
                             f"cannot open {name}: {type(e).__name__}: {e}", error=True)
            return
        self.size = (scene.settings.width, scene.settings.height)
        self.selected = None
        self.opened_at = started
        self._scene_opened(self.renderer.compiled)
        self.set_message(f"loaded {scene.name}")

    def say_first_image(self, drawn: bool):
        """After a frame that drew a new image: the first one of a scene opened says on standard
        error how long it took from the window's start, or from the panel's asking for the
        scene (bench-style scripts time the viewer by this line)."""
        if drawn and self.opened_at is not None:
            print(f"first image of {self.renderer.scene.name} in {time.perf_counter() - self.opened_at:.2f} s",
                  file=sys.stderr)
            self.opened_at = None

    def _scene_opened(self, compiled):
        """Movement at the scene's scale (the wheel changes it from there), and the panel's file
        field naming the scene's file, if it has one."""
        self.controls.speed = speed_for(compiled.scene.camera, compiled.radius)
        self.camera_fields = {}       # (switch_camera_type) another scene's cameras' fields forgotten
        if compiled.scene.source:
            self.scene_file = compiled.scene.source

    def _build_progress(self, name: str):
        """A progress callback for a scene's BVH build, from the worker thread: the window, live
        in its own thread, shows how far it is, and once it is built, that the kernels are
        coming (they began building beside the tree: Renderer.set_scene). A tree read from the
        cache before the device is open leaves the status as it is (_start: the device's opening
        comes next)."""
        def show(fraction):
            if fraction < 1:
                self._status = (f"building the BVH of {name}", fraction)
            elif hasattr(self, "backend"):
                self._status = self._preparing(name)
        return show

    def _preparing(self, name: str) -> tuple:
        return f"preparing the kernels for {name} on {self.backend.device.name}", None
