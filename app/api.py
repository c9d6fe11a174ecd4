"""pathtrace's Python API (docs/python.md): load a scene (a file, a built-in, or dicts of the TOML
format), change it, render it to NumPy arrays, and write, tonemap, denoise or show the images.
The command line is built on these functions.

Images are NumPy arrays of linear radiance, (height, width, 3) float32, row 0 at the top; sizes
are (width, height) in pixels. A scene rendered again is not compiled again: its BVH and buffers
stay on the device between renders, and only what changed since the last render (the camera,
the settings, the materials, the environment) is uploaded again; a change of geometry (spheres
or meshes) compiles it anew."""

import operator
import os
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from pathtrace.errors import UserError, cut, short, warn
from pathtrace.rendering.choices import INTEGRATORS, TONEMAPS
from pathtrace.scene.description import Scene
from pathtrace.scene.validate import SETTING_RANGES, check_scene, check_tables, russian_roulette
from pathtrace.scene.validate import integer as _integer

AOVS = ("albedo", "normal", "depth")


def load(path_or_name) -> Scene:
    """A scene from a .toml or Mitsuba 3 .xml file, or a built-in scene by name ('simple',
    'demo', 'cornell-box', ...; `pathtrace scenes` lists them)."""
    from pathtrace.scene import load_scene
    if not isinstance(path_or_name, (str, Path)):
        raise UserError(f"load: give a file path or a built-in scene's name, got {short(path_or_name)}")
    return load_scene(str(path_or_name))


def load_dict(data: dict, name: str = "scene", folder=".") -> Scene:
    """A scene written in Python: the tables of the TOML format (docs/scene-format.md) as dicts,
    lists (or tuples, or NumPy arrays) and numbers. Mesh and map files it names are looked up
    relative to `folder`."""
    from pathtrace.scene.toml_reader import read_scene_dict
    if not isinstance(data, dict):
        raise UserError(f"load_dict: the scene must be a dict of the TOML format's tables, got {short(data)}")
    check_tables(data, "load_dict")
    return read_scene_dict(data, name, folder)


def material(data: dict):
    """A Material from a table of the TOML format's [materials], e.g.
    {"type": "roughconductor", "material": "Au", "alpha": 0.2}; assign it to a scene's material
    by name or row: scene.materials["gold"] = pathtrace.material({...})."""
    from pathtrace.scene.toml_reader import read_material_dict
    check_tables(data, "material")
    return read_material_dict(data)


def devices() -> list:
    """The OpenCL devices found, each with .index, .name, .kind ('GPU' or 'CPU') and
    .describe(); `device=` takes an index, a kind, or part of a name."""
    from pathtrace.device.opencl import list_devices
    return list_devices()


def queue_plans(scene) -> list:
    """What settings.path_queue PATH_QUEUE_AUTO chose for `scene`'s last render, in words, one
    per device (pathtrace.rendering.renderer: the plan and each plan's trial); empty where it was not
    asked for or the scene was not rendered."""
    prepared = scene.__dict__.get("_prepared")
    return prepared.group.queue_plans() if prepared else []


def programs_used(scene) -> list:
    """Where the generic program (pathtrace.device.programs) drew samples of `scene`'s last render, in
    words, one per device that it did on; empty where the scenes' own programs drew them all."""
    prepared = scene.__dict__.get("_prepared")
    return prepared.group.programs_used() if prepared else []


_backends = {}            # device specs -> opened backends, kept for the next render
_opening_lock = threading.Lock()    # a DevicesOpening's thread and a render's asking at once open once


def open_devices(device="auto") -> list:
    """The backends for `device`: a spec as `--device` takes it ('auto', 'gpu', 'cpu', 'gpu:1',
    an index, part of a name, or 'all') or a list of specs. Opened once and kept. A
    DevicesOpening begun earlier gives its own, once opened."""
    from pathtrace.device.opencl import choose_devices
    if isinstance(device, DevicesOpening):
        return device.result()
    specs = tuple(_device_spec(s) for s in (device if isinstance(device, (list, tuple)) else (device,)))
    if not specs or not all(isinstance(s, str) for s in specs):
        raise UserError(f"device: give a device spec such as 'auto', 'gpu', 'cpu:0' or a list of them, "
                        f"got {short(device)}")
    with _opening_lock:
        if specs not in _backends:
            _backends[specs] = choose_devices(list(specs))
        return _backends[specs]


def _device_spec(spec):
    """A device spec, an index of `pathtrace devices` given as an integer (a NumPy one too, not
    a bool) as the string --device takes; anything else as it is, for the caller to refuse."""
    if isinstance(spec, (bool, str)):
        return spec
    try:
        return str(operator.index(spec))
    except TypeError:
        return spec


class DevicesOpening:
    """open_devices(device) begun at once, in a thread of its own, so that a command reads and
    compiles its scene meanwhile (prepare): the drivers start and build programs with the GIL
    released (pathtrace.device.loader). Once the devices are open, the thread builds their BVH
    build kernels (pathtrace.compiler.builder.builder_for), which a tree not in the cache needs,
    while the scene's own program builds beside them (Renderer.set_scene): on a first start on
    an H200 the two had been built one after the other (0.5-0.8 s, then 1.5-1.9 s). Where the
    scene's tree is known by then to need no device (builder_wanted: the host built it, or the
    cache held it), it builds none."""

    def __init__(self, device="auto"):
        from pathtrace.compiler.builder import tree_unknown
        tree_unknown()          # this opening's scene is yet to be compiled
        self.seconds = 0.0      # what the opening took, in its thread (the builders' build not included)
        self._opened = Future()
        pool = ThreadPoolExecutor(1, thread_name_prefix="open-devices")
        pool.submit(self._open, device)
        pool.shutdown(wait=False)       # the thread ends with its work; the interpreter waits for it

    def _open(self, device):
        from pathtrace.compiler.builder import builder_for, builder_wanted, tree_likely
        start = time.perf_counter()
        try:
            backends = open_devices(device)
        except BaseException as e:
            self.seconds = time.perf_counter() - start
            self._opened.set_exception(e)
            return
        self.seconds = time.perf_counter() - start
        self._opened.set_result(backends)
        try:
            for backend in backends if builder_wanted() else ():
                builder_for(backend.queue, ahead=tree_likely())
        except Exception:       # a tree's build asks again (builder_for keeps no failure), and says why
            pass

    def result(self) -> list:
        """open_devices' backends, once opened, or its error."""
        return self._opened.result()

    def opened(self) -> bool:
        """Whether the devices are open (not failed, nor still opening)."""
        return self._opened.done() and self._opened.exception() is None


@dataclass
class Snapshot:
    """An image as progressive() yields it: `spp` samples per pixel after `seconds` of rendering
    (device time, from the first sample; compiling and reading back excluded). `aovs` holds the
    auxiliary images that were asked for. Shown inline in Jupyter."""
    spp: int
    seconds: float
    image: np.ndarray
    aovs: dict

    def _repr_png_(self):
        return png_bytes(self.image)

    def __repr__(self) -> str:
        h, w = self.image.shape[:2]
        return f"<Snapshot {w}x{h}, {self.spp} spp after {self.seconds:.3g} s" + \
            (f", aovs {', '.join(self.aovs)}>" if self.aovs else ">")


def checked_size(size) -> tuple:
    """(width, height) of a size given as two integers in range, else a UserError."""
    if not isinstance(size, (tuple, list)) or len(size) != 2:
        raise UserError(f"size: give (width, height), got {short(size)}")
    return tuple(_integer("size", v, *SETTING_RANGES["width"]) for v in size)


def settings_for(scene: Scene, spp=None, size=None, seed=None, max_depth=None, rr=None, nee=None, integrator=None):
    """The scene's render settings with the given ones in their place, checked (the scene's
    own fields, which a user may have changed since loading, first)."""
    check_scene(scene)
    s = scene.settings
    changes = {}
    if spp is not None:
        changes["spp"] = _integer("spp", spp, *SETTING_RANGES["spp"])
    if size is not None:
        changes["width"], changes["height"] = checked_size(size)
    if seed is not None:
        changes["seed"] = _integer("seed", seed, *SETTING_RANGES["seed"])
    if max_depth is not None:
        changes["max_depth"] = _integer("max_depth", max_depth, *SETTING_RANGES["max_depth"])
    if rr is not None:
        changes["russian_roulette"] = russian_roulette("rr", rr)
    if nee is not None:
        if not isinstance(nee, (bool, int, np.bool_, np.integer)):
            raise UserError(f"nee: give True or False, got {short(nee)}")
        changes["nee"] = bool(nee)
    if integrator is not None:
        if not isinstance(integrator, str) or integrator not in INTEGRATORS:
            raise UserError(f"integrator: give one of {', '.join(INTEGRATORS)}, got {short(integrator)}")
        changes["integrator"] = integrator
    settings = replace(s, **changes)
    if not settings.paths_end:
        raise UserError("rr 'off' needs max_depth >= 1, or paths would never end")
    return settings


class _Prepared:
    """A scene compiled and uploaded to a group of devices, with what it was compiled from, so
    that the next render uploads only what changed."""

    def __init__(self, scene: Scene, device, build_progress=None, phases=None, settings=None, aovs: bool = False):
        from pathtrace.compiler.compiled import compile_before_devices
        from pathtrace.rendering.multidevice import DeviceGroup
        start = time.perf_counter()
        compiled = compile_before_devices(scene, build_progress)     # while the devices open
        self.geometry = compiled.geometry_digest
        asked = time.perf_counter()
        self.backends = open_devices(device)
        waited = time.perf_counter() - asked
        self.group = DeviceGroup(self.backends, compiled, settings=settings, aovs=aovs)
        if phases:
            # the renderers' construction includes building the kernels specialised to the
            # scene, which it does not report on its own: what is left of it once the tree is
            # built; the compiling's time leaves out the wait for the devices, which have a line
            # of their own, where the tree was built after it
            compiling = compiled.tree_ended - start - (waited if compiled.tree_ended > asked else 0.0)
            phases(f"compiled the scene ({_contents(compiled)}, BVH in {compiled.bvh_seconds:.2f} s)", compiling)
            preparing = time.perf_counter() - max(compiled.tree_ended, asked + waited)
            phases(f"prepared the renderer{'s' * (len(self.backends) > 1)}", preparing)
        self.environment = _environment_key(scene.environment)
        self.lights = _lights_key(scene.lights)

    def update(self, scene: Scene, settings, aovs: bool):
        """Brings the devices up to date with the scene and restarts the image."""
        compiled = self.group.compiled
        environment = _environment_key(scene.environment)
        rows, textures = compiled.material_source
        materials_changed = not _same_rows(scene.materials.rows, rows) or scene.materials.textures != textures
        lights = _lights_key(scene.lights)
        for r in self.group.renderers:
            if environment != self.environment:
                r.set_environment(scene.environment)
            elif materials_changed or lights != self.lights:
                r.upload_materials()
            r.set_camera(scene.camera)
            r.set_settings(**{k: getattr(settings, k) for k in ("max_depth", "russian_roulette", "seed", "nee",
                                                                "filter", "light_sampler", "path_queue", "path_sort",
                                                                "integrator")})
            r.resize(settings.width, settings.height)
            r.set_aovs(aovs)
        self.environment, self.lights = environment, lights


def prepare(scene: Scene, device="auto", build_progress=None, phases=None, settings=None,
            aovs: bool = False) -> _Prepared:
    """The compiled, uploaded form of `scene` on `device` (open_devices), made once and kept
    with the scene (so that it goes when the scene goes); compiled anew if the scene's geometry
    changed or the devices differ. phases(what, seconds) is called as each step of making it
    ends: compiling the scene, then preparing the renderers. `settings` (default: the scene's)
    and `aovs`, those of the render it is made for: the renderers' first programs are built for
    them, beside the tree (a render's nee=False had a program built for the scene's NEE first,
    and its AOVs' after the tree)."""
    from pathtrace.compiler.geometry_cache import geometry_digest
    kept = scene.__dict__.get("_prepared")
    if kept is not None and kept.geometry == geometry_digest(scene) and kept.backends == open_devices(device):
        return kept
    scene.__dict__.pop("_prepared", None)    # free the old buffers before making new ones
    scene._prepared = _Prepared(scene, device, build_progress, phases, settings, aovs)
    return scene._prepared


def _contents(compiled) -> str:
    """What a compiled scene holds, in words: '5 spheres', '126,504 triangles, 1 sphere'."""
    n_shapes = len(compiled.shape_prims)
    counts = [(compiled.num_triangles - n_shapes, "triangle"), (compiled.num_spheres, "sphere"),
              (n_shapes, "analytic shape")]
    return ", ".join(f"{n:,} {what}{'s' * (n != 1)}" for n, what in counts if n) or "nothing"


def _same_rows(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two material tables hold the same bytes: compared field by field, a table of a
    million materials (spheres1M) took 0.3 s of every render; bytes also find a NaN unchanged."""
    return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(
        np.ascontiguousarray(a).view(np.uint8), np.ascontiguousarray(b).view(np.uint8))


def _environment_key(environment):
    return (id(environment), id(environment.image), float(environment.intensity), float(environment.rotation),
            tuple(environment.up), bool(environment.mirrored))


def _lights_key(lights) -> tuple:
    """What the delta lights are, to tell whether they changed since the last render."""
    return tuple((light.name, *(np.asarray(getattr(light, f)).tobytes() for f in light.fields)) for light in lights)


def progressive(scene, spp=None, steps=None, size=None, device="auto", seed=None, max_depth=None,
                rr=None, nee=None, aovs=(), progress=False, build_progress=None, phases=None, integrator=None):
    """Renders `scene` (a Scene, or what load() takes) and yields a Snapshot each time the image
    reaches one of `steps` samples per pixel (default: 1, 2, 4, ... up to spp, and spp; spp
    defaults to the scene's). Given spp, no step may exceed it; without it, the last step is as
    far as the render goes. Arguments as for render(). Stopping the iteration early stops the
    render."""
    scene = scene if isinstance(scene, Scene) else load(scene)
    settings = settings_for(scene, spp, size, seed, max_depth, rr, nee, integrator)
    steps = _steps(steps, settings.spp)
    if spp is not None and steps[-1] > settings.spp:
        raise UserError(f"steps: {steps[-1]} is more samples per pixel than spp ({settings.spp}); "
                        "leave spp out for the steps alone to say how far to render")
    aovs = _aov_names(aovs)
    _check_callbacks(progress=progress, build_progress=build_progress, phases=phases)
    prepared = prepare(scene, device, build_progress, phases, settings, bool(aovs))
    prepared.update(scene, settings, bool(aovs))
    group = prepared.group
    # path_queue "auto": chosen for the whole render, not its first step; its trials' samples kept
    # where the first step has as many
    group.choose_queue_plans(steps[-1], keep_up_to=steps[0])
    on_progress, close = _progress(progress, scene.name, settings, steps[-1])
    if on_progress:
        on_progress(0)
    seconds = 0.0
    try:
        for target in steps:
            start = time.perf_counter()
            group.render(target, on_progress)
            seconds += time.perf_counter() - start
            read = group.read_aovs() if aovs else {}
            yield Snapshot(target, seconds, group.mean(), {name: read[name] for name in aovs})
    finally:
        close()
    dropped = group.dropped_samples()
    if dropped:
        warn(f"{scene.name}: {dropped} of {steps[-1] * settings.width * settings.height} samples were NaN "
             f"or infinite and were left out (as black)")


def render(scene, spp=None, size=None, device="auto", seed=None, max_depth=None, rr=None, nee=None,
           aovs=(), progress=False, build_progress=None, phases=None, integrator=None):
    """Renders `scene` (a Scene, or what load() takes) and returns the image, (height, width, 3)
    float32 linear radiance. With `aovs` (names from "albedo", "normal", "depth"), returns a dict
    of "image" and each of them: albedo and normal (H, W, 3), the first hit's distance (H, W), 0
    where the camera ray escapes; averaged over each pixel, from the first 16 samples.

    spp: samples per pixel; size: (width, height); seed: 0 to 2^32 - 1; max_depth: the longest
    path in vertices (1: emitters seen directly, 0: no limit); rr: how paths end ("throughput",
    "albedo" or "off"); nee: next-event estimation; integrator: "path" (the path tracer), "bdpt"
    (bidirectional path tracing) or "ptracer" (its light tracing alone); each defaults to the
    scene's settings.
    device: as open_devices() takes it; several devices share the samples. progress: True for a
    progress bar (a notebook's, in Jupyter), or a function called with the samples per pixel
    done (0 as the first samples start, after the scene is compiled); build_progress: a function called with the fraction of a large BVH build done;
    phases: a function called with (what, seconds) as each step before the first sample ends,
    where the scene was not compiled already: "compiled the scene (...)", "prepared the renderer"."""
    scene = scene if isinstance(scene, Scene) else load(scene)
    # one snapshot, of the whole render: each step of progressive's would read the image back,
    # and start its launches again from one sample (progressive checks both)
    final = scene.settings.spp if spp is None else spp
    for snapshot in progressive(scene, spp, [final], size, device, seed, max_depth, rr, nee, aovs,
                                progress, build_progress, phases, integrator):
        pass
    return {"image": snapshot.image, **snapshot.aovs} if snapshot.aovs else snapshot.image


def _steps(steps, spp: int) -> list:
    if steps is None:
        return sorted({min(1 << k, spp) for k in range(spp.bit_length() + 1)})
    if isinstance(steps, (str, bytes)) or not hasattr(steps, "__iter__"):
        raise UserError(f"steps: give a list of increasing sample counts, got {short(steps)}")
    steps = [_integer("steps", s, 1, 2**31 - 1) for s in steps]
    if not steps or steps != sorted(set(steps)):
        raise UserError(f"steps: give increasing sample counts, got {short(steps)}")
    return steps


def _aov_names(aovs) -> tuple:
    if not isinstance(aovs, str) and not hasattr(aovs or (), "__iter__"):
        raise UserError(f"aovs: give names from {', '.join(AOVS)}, got {short(aovs)}")
    names = (aovs,) if isinstance(aovs, str) else tuple(aovs or ())
    unknown = [n for n in names if n not in AOVS]
    if unknown:
        raise UserError(f"aovs: {short(unknown[0])} is not one of {', '.join(AOVS)}")
    return tuple(dict.fromkeys(names))


def _check_callbacks(**given):
    """The callback arguments: a function or None (progress also True or False), one line
    naming the argument otherwise, not a TypeError from the middle of the render."""
    for name, value in given.items():
        if not (value is None or callable(value) or (name == "progress" and isinstance(value, bool))):
            allowed = "True, False or a function" if name == "progress" else "a function or None"
            raise UserError(f"{name}: give {allowed}, got {short(value)}")


def _progress(progress, name: str, settings, total: int):
    """(on_progress(samples done), close()) for a progress argument."""
    if callable(progress):
        return progress, lambda: None
    if not progress:
        return None, lambda: None
    from tqdm.auto import tqdm
    bar = tqdm(total=total, desc=f"{name} {settings.width}x{settings.height}", unit="spp")
    return (lambda done: bar.update(done - bar.n)), bar.close


def denoise(image: np.ndarray, albedo: np.ndarray = None, normal: np.ndarray = None,
            quality: str = "high") -> np.ndarray:
    """The image denoised by Intel Open Image Denoise, guided by the albedo and normal that
    render(aovs=("albedo", "normal")) gives (better) or not; quality "high", "balanced" or
    "fast". Each array (H, W, 3)."""
    from pathtrace.io.denoiser import QUALITIES, Denoiser
    if quality not in QUALITIES:
        raise UserError(f"quality: give one of {', '.join(QUALITIES)}, got {short(quality)}")
    image = _rgb("image", image)
    guides = [None if a is None else _rgb(name, a, image.shape) for name, a in (("albedo", albedo), ("normal", normal))]
    if guides[0] is None and guides[1] is not None:
        raise UserError("denoise: a normal guide needs the albedo guide too (Open Image Denoise's rule)")
    with Denoiser(quality) as denoiser:
        return denoiser(image, *guides)


def _rgb(name: str, image, shape=None) -> np.ndarray:
    """An (H, W, 3) float32 array from an image argument; (H, W) is taken as grey. An array of
    integers is refused: it is a display image (tonemap's uint8), whose 0-255 would be taken as
    radiance."""
    if isinstance(image, np.ndarray) and image.dtype.kind in "biu":
        raise UserError(f"{name}: an array of {image.dtype} is a display image, not radiance; give linear radiance "
                        "as floats (what render returns), or write a uint8 image with an image library")
    try:
        with np.errstate(over="ignore"):          # beyond float32: infinite, refused below
            a = np.asarray(image, np.float32)
    except (TypeError, ValueError):
        raise UserError(f"{name}: give an (H, W, 3) or (H, W) array of numbers, got {short(image)}") from None
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=-1)
    if a.ndim != 3 or a.shape[-1] != 3 or 0 in a.shape:
        raise UserError(f"{name}: give an (H, W, 3) or (H, W) array, got shape {a.shape}")
    if shape is not None and a.shape != shape:
        raise UserError(f"{name}: its shape {a.shape} is not the image's {shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        # no display value for them, the denoiser spreads them over their neighbours as finite
        # garbage, and pathtrace's readers refuse a file that holds them
        y, x, _ = np.argwhere(bad)[0]
        raise UserError(f"{name}: {int(bad.any(axis=-1).sum())} pixel(s) hold NaN or infinity (beyond float32), "
                        f"the first at x={x}, y={y}")
    return np.ascontiguousarray(a)


def tonemap(image: np.ndarray, exposure: float = 0.0, curve: str = "standard") -> np.ndarray:
    """Linear radiance to display sRGB, (H, W, 3) uint8: exposure in stops, then the tone curve
    ("standard" clips at 1, "aces" is Narkowicz's fit of ACES), then the sRGB transfer function;
    what a .png output holds."""
    from pathtrace.io.tonecurve import to_8bit
    from pathtrace.io.tonecurve import tonemap as display
    if not isinstance(curve, str) or curve not in TONEMAPS:      # an array's `in` is elementwise
        raise UserError(f"curve: give one of {', '.join(TONEMAPS)}, got {short(curve)}")
    if isinstance(exposure, bool) or not isinstance(exposure, (int, float, np.number)) or not -100 <= exposure <= 100:
        raise UserError(f"exposure: give stops from -100 to 100, got {short(exposure)}")
    return to_8bit(display(_rgb("image", image), float(exposure), curve))


def write(path, image: np.ndarray, exposure: float = 0.0, curve: str = "standard"):
    """Writes an image file, atomically: .png and .jpg tonemapped (as tonemap() does), .exr,
    .hdr and .pfm as linear float radiance. (H, W) arrays (a depth) are written as grey."""
    from pathtrace.io.images import write_image
    if not isinstance(path, (str, Path)):
        raise UserError(f"path: give a file name (str or Path), got {short(path)}")
    tonemap(np.zeros((1, 1, 3)), exposure, curve)         # the same checks
    write_image(Path(path), _rgb("image", image), float(exposure), curve, what="path")


def png_bytes(image: np.ndarray, exposure: float = 0.0, curve: str = "standard") -> bytes:
    """The image tonemapped and encoded as PNG."""
    import cv2
    ok, encoded = cv2.imencode(".png", np.ascontiguousarray(tonemap(image, exposure, curve)[..., ::-1]))
    return encoded.tobytes()


@dataclass
class Picture:
    """An image as Jupyter shows it inline (show())."""
    image: np.ndarray
    exposure: float = 0.0
    curve: str = "standard"

    def _repr_png_(self):
        return png_bytes(self.image, self.exposure, self.curve)

    def __repr__(self) -> str:
        h, w = self.image.shape[:2]
        return f"<Picture {w}x{h}, exposure {self.exposure:g}, {self.curve} tone curve>"


def show(image: np.ndarray, exposure: float = 0.0, curve: str = "standard") -> Picture:
    """An object that Jupyter displays as the tonemapped image (the last expression of a cell,
    or IPython.display.display(...))."""
    tonemap(np.zeros((1, 1, 3)), exposure, curve)
    return Picture(_rgb("image", image), float(exposure), curve)


def view(scene="simple", device: str = "auto", size=None, frames: int = None,
         screenshot_dir="screenshots", screenshot: bool = False):
    """Opens the interactive viewer on `scene` (a Scene, what load() takes, or a function that
    returns a Scene) and returns when its window is closed, or after `frames` frames;
    screenshot: take one when closing. Needs a display. The window opens at once: the scene is
    read, the device opened and the kernels compiled while it says so."""
    from pathtrace.viewer.needs_display import require_display
    from pathtrace.viewer.window import Viewer
    device = _device_spec(device)
    if not isinstance(device, str):
        raise UserError("device: the viewer renders on one device; give one spec (several are for render)")
    require_display(scene if isinstance(scene, str) else "simple")    # before any device work
    if frames is not None:
        frames = _integer("frames", frames, 1, 2**31 - 1)
    if size is not None:
        size = checked_size(size)           # before the window opens at it
    if screenshot and os.path.exists(screenshot_dir) and not os.path.isdir(screenshot_dir):
        raise UserError(f"screenshot_dir: '{cut(str(screenshot_dir), 200)}' is a file, not a folder")   # not after the run

    def read():
        """The scene, read in a thread of its own while the window opens and says so."""
        given = scene if isinstance(scene, Scene) else scene() if callable(scene) else load(scene)
        if not isinstance(given, Scene):
            raise UserError(f"scene: the function gave no scene, but {short(given)}")
        return given if size is None else replace(given, settings=settings_for(given, size=size))
    opening = DevicesOpening(device)        # while the window opens and the scene is read
    with ThreadPoolExecutor(1, thread_name_prefix="read-scene") as pool:
        reading = pool.submit(read)         # beside the window's opening (0.2-0.4 s under Xvfb)
        viewer = Viewer(lambda: opening.result()[0], reading.result, screenshot_dir, image_size=size)
    written = None
    try:
        viewer.run(frames)
        if screenshot:
            written = viewer.screenshot(scripted=True)     # a failure is the command's, not the panel's
    finally:
        viewer.close()
    if written is not None and written.exception() is not None:
        raise written.exception()
