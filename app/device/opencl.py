"""OpenCL devices: listing them, choosing one from the --device flag, and building the kernels
(with a binary cache where the driver keeps none, so that a second start does not recompile)."""

import functools
import hashlib
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pyopencl as cl

from pathtrace.io.cache_files import cache_dir, read_entry, write_entry
from pathtrace.errors import UserError, format_bytes, short
from pathtrace.device.features import Features
from pathtrace.device.loader import new_context, start_drivers
from pathtrace.device.occupancy import REPORT, TUNING_RULE, build_for_occupancy, is_nvidia
from pathtrace.device.quiet_build import build_quietly
from pathtrace.device.programs import Programs, default_mode
from pathtrace.resources import resource_dir

# The order in which the kernel files are joined into one program: the basics, the texture
# kernels of the types a scene uses (app/textures/registry.py: kernel_parts), the shapes and
# traversal (with alpha masks where a scene has them), the shading of textured materials, the
# BSDFs of the material registry and their generated dispatch, the environment, the light types
# a scene has and their dispatch (app/lights/registry.py), its camera and pixel filter, the media
# where it has them, the rest, and bidirectional path tracing where a render asks for it.
BASIC_FILES = ("inlining.h", "types.h", "vector.cl", "color.cl", "rng.cl", "sampling.cl", "scene.cl",
               "divergence.cl")
SHAPE_FILES = ("spawn.cl", "shapes/sphere_range.cl", "shapes/triangle.cl")
BSDF_FILES = ("bsdf.cl", "fresnel.cl", "microfacet.cl", "coating.cl", "interface.cl", "phase.cl")
MEDIA_FILES = ("media/homogeneous.cl", "volume.cl")
LATER_FILES = ("path_queue.cl", "path_sort.cl", "integrator.cl", "aovs.cl")
DISPLAY_FILE = "display.cl"     # in the programs of every kernel (the generic ones, which the window uses)
BDPT_FILES = ("bdpt_vertex.cl", "bdpt_subpaths.cl", "splats.cl", "photons.cl", "bdpt.cl")

# No -cl-fast-relaxed-math: it implies finite math, and the kernels rely on INFINITY. Denormal
# floats flushed to zero: an x86 core takes a microcode assist of about a hundred cycles on each
# denormal operand or result, and some scenes' paths make many (PoCL rendered the Cornell box
# 2.5-4x faster with them flushed), and on an H200 the flush-to-zero instructions took 2-11 % off
# every scene measured (docs/notes/performance-2026-11.md, 2026-11-29). A value below 1.2e-38 is
# as good as zero to a radiance or a density, and the kernels handle zero densities and zero
# direction components already (kernels/sampling.cl: mis_weight; the slab test).
BUILD_OPTIONS = ("-cl-mad-enable", "-cl-no-signed-zeros", "-cl-denorms-are-zero")
# A cache entry's payload (app/io/cache_files.py: a checksum, then the payload): the build options
# the binary was made with (NUL separated) and a newline, the binary.
CACHE_FORMAT = "3"


def kernel_source(extra: str = "", features: Features = Features()) -> str:
    """The kernels as one source text, each file introduced by a #line marker so that compiler
    messages name the file and line."""
    from pathtrace import cameras, filters, lights, shapes
    from pathtrace.materials import dispatch_source, kernel_files, tag_source
    from pathtrace.textures import kernel_parts

    folder = resource_dir("kernels")
    texts = [(name, (folder / name).read_text()) for name in BASIC_FILES]
    texts += [(name, text if text is not None else (folder / name).read_text())
              for name, text in kernel_parts(features.textures)]
    texts.append(("app/materials/registry.py: tag_source", tag_source()))
    # the transforms of instances and analytic shapes, where the scene has either
    moved = ("transform.cl",) if features.shapes or features.instances else ()
    texts += [(name, (folder / name).read_text())
              for name in (*SHAPE_FILES, *moved, *shapes.kernel_files(features.shapes))]
    if features.shapes:
        texts += [("app/shapes/registry.py: dispatch_source", shapes.dispatch_source(features.shapes)),
                  ("app/shapes/texture_uv.py: texture_uv_source", shapes.texture_uv_source()),
                  ("shapes/analytic.cl", (folder / "shapes/analytic.cl").read_text())]
    files = (*(("masks.cl",) if features.masks else ()), "bvh.cl", "frame.cl",
             *(("normal_maps.cl",) if features.normal_maps else ()),
             *(("shading.cl",) if features.textures else ()), *BSDF_FILES, *kernel_files(features.bsdfs))
    texts += [(name, (folder / name).read_text()) for name in files]
    texts.append(("app/materials/registry.py: dispatch_source", dispatch_source(features.bsdfs)))
    parts = [("environment.cl", None), *lights.kernel_parts(features.lights, features.light_tree, bool(features.bdpt)),
             *cameras.kernel_parts(features.camera), *filters.kernel_parts(features.filter)]
    texts += [(name, text if text is not None else (folder / name).read_text()) for name, text in parts]
    texts += [(name, (folder / name).read_text())
              for name in (*(MEDIA_FILES if features.media else ()), *LATER_FILES,
                           *((DISPLAY_FILE,) if features.kernels == "all" else ()),
                           *(BDPT_FILES if features.bdpt else ()))]
    if extra:
        texts.append(("extra", extra))
    return "\n".join(f'#line 1 "{name}"\n{text}' for name, text in texts)


@dataclass
class Device:
    index: int
    platform: cl.Platform
    device: cl.Device

    @property
    def name(self) -> str:
        return self.device.name.strip()

    @property
    def kind(self) -> str:
        return "GPU" if self.device.type & cl.device_type.GPU else "CPU" \
            if self.device.type & cl.device_type.CPU else "other"

    def describe(self) -> str:
        return f"{self.name} ({self.kind}, {self.platform.name.strip()})"


HOW_TO_GET_ONE = ("for the CPU without root, pip install pocl-binary-distribution (pathtrace's extra [cpu]); "
                  "on Debian/Ubuntu, apt install pocl-opencl-icd; for a GPU, its vendor's OpenCL driver")


def no_device() -> str:
    """The one line wherever no device is found; where POCL_CACHE_DIR cannot be written, where
    PoCL lists no device at all, the line says so first."""
    from pathtrace.device.driver_caches import writable
    folder = os.environ.get("POCL_CACHE_DIR")
    if folder and not writable(folder):
        return (f"no OpenCL device found (PoCL lists none where POCL_CACHE_DIR, {folder}, cannot be written): "
                + HOW_TO_GET_ONE)
    return f"no OpenCL device found: {HOW_TO_GET_ONE}"


def list_devices() -> list[Device]:
    devices = []
    start_drivers()
    try:
        platforms = cl.get_platforms()
    except cl.Error:
        platforms = []
    for platform in platforms:
        try:
            found = platform.get_devices()
        except cl.Error:
            continue
        first = len(devices)      # not inside the generator: extend() grows the list as it goes
        devices.extend(Device(first + i, platform, d) for i, d in enumerate(found))
    return devices


@dataclass
class BuildResult:
    program: cl.Program
    seconds: float
    cached: bool


def program_options(device: cl.Device, features: Features) -> list[str]:
    """The build options of the kernels specialised to `features` and to the kind of device
    (CPU_DEVICE: on CPUs the samplers' azimuths take cospi: kernels/sampling.cl, COS_TURNS;
    NVIDIA_PTX: NVIDIA's compiler takes inline PTX, for float atomics: kernels/splats.cl)."""
    options = list(BUILD_OPTIONS) + [f"-D{d}" for d in features.defines()]
    if device.type & cl.device_type.CPU:
        options.append("-DCPU_DEVICE")
    if is_nvidia(device):
        options.append("-DNVIDIA_PTX")
    return options


def build_program(context: cl.Context, device: cl.Device, extra: str = "",
                  use_cache: bool = True, features: Features = Features(), tune: bool = True) -> BuildResult:
    """Builds the kernels specialised to `features` for one device. `tune`: see build_cached."""
    return build_cached(context, device, kernel_source(extra, features), program_options(device, features),
                        use_cache, tune)


def program_entry(device: cl.Device, features: Features = Features(), extra: str = "", tune: bool = True) -> Path:
    """The cache entry of the program build_program builds for `features` (cache_entry)."""
    return cache_entry(device, kernel_source(extra, features), program_options(device, features), tune)


def cache_entry(device: cl.Device, source: str, options: list[str], tune: bool) -> Path:
    """Where the binary of a build is cached: keyed by the source, the options, whether it is
    tuned and under which rule (occupancy.TUNING_RULE), the exact device and driver and the
    entry's format."""
    tune = tune and is_nvidia(device)
    key = hashlib.sha256("\0".join([
        CACHE_FORMAT, source, " ".join(options), f"tuned, {TUNING_RULE}" if tune else "",
        device.platform.name, device.platform.version,
        device.name, device.version, device.driver_version]).encode()).hexdigest()[:32]
    return cache_dir() / f"{key}.bin"


def keeps_own_cache(device: cl.Device) -> bool:
    """Whether the driver caches what it compiles well enough that pathtrace's cache only costs:
    PoCL keeps each program it has built (a rebuild from source reads it back in 0.06 s) and each
    kernel it has compiled for a work-group size. Asking PoCL for a program's binary compiles
    every kernel in it for a generic work-group size first, about 4 s for the render program on
    two cores, kernels a scene may never launch and which its launches compile again for their
    size (docs/performance.md)."""
    return device.platform.name.strip() == "Portable Computing Language"


def build_cached(context: cl.Context, device: cl.Device, source: str, options: list[str],
                 use_cache: bool = True, tune: bool = True) -> BuildResult:
    """Builds a program for one device. Unless the driver keeps its own cache, the binary is
    cached under cache_dir() (cache_entry); where it does, an empty entry beside it marks that
    the driver's cache holds the build (built_before). `tune`: on NVIDIA, try the register caps
    of app/device/occupancy.py (up to four more builds of the program)."""
    marks = use_cache and keeps_own_cache(device)
    use_cache = use_cache and not marks
    path = cache_entry(device, source, options, tune)
    tune = tune and is_nvidia(device)
    start = time.perf_counter()
    cached = _read_cached(path) if use_cache else None
    if cached is not None:
        built_with, binary = cached
        try:
            program = build_quietly(cl.Program(context, [device], [binary]), built_with, report=REPORT in built_with)
            return BuildResult(program, time.perf_counter() - start, True)
        except cl.Error:
            pass   # a stale or foreign binary: rebuild from source below
    if tune:
        program, options = build_for_occupancy(context, device, source, options)
    else:
        program = build_quietly(cl.Program(context, source), options, [device])
    seconds = time.perf_counter() - start
    if use_cache:
        binary = program.get_info(cl.program_info.BINARIES)[0]
        if binary:
            # the options it was built with go with it: a register cap applies when a driver
            # compiles the cached intermediate code (NVIDIA's PTX) for the device
            write_entry(path, "\0".join(options).encode() + b"\n", binary)
    elif marks:
        write_entry(path.with_suffix(".built"))
    return BuildResult(program, seconds, False)


def built_before(device: cl.Device, entry: Path) -> bool:
    """Whether the program whose cache entry is `entry` (cache_entry) builds from a cache on
    `device`: its binary is in pathtrace's cache, or the driver keeps its own cache and
    build_cached marked the build (PoCL: else its first build compiles it afresh)."""
    return entry.is_file() or (keeps_own_cache(device) and entry.with_suffix(".built").is_file())


def _read_cached(path: Path):
    """A cached binary and the build options it was made with, or None where there is none or
    it is damaged (pathtrace.io.cache_files)."""
    data = read_entry(path)
    data = bytes(data) if data is not None else b""
    if b"\n" not in data:
        return None
    options, binary = data.split(b"\n", 1)
    return ([o for o in options.decode().split("\0") if o], binary) if binary else None


@dataclass
class Backend:
    """A chosen device with its context and queue, and its programs (pathtrace.device.programs): the
    generic program (Features.generic_program) and those specialised to scenes' features, built
    when first asked for. `opened`: what open_device built to show that the platform builds
    kernels. `mode`: one of programs.PROGRAM_MODES, how a renderer on it chooses among them."""
    device: Device
    context: cl.Context
    queue: cl.CommandQueue
    opened: BuildResult
    extra: str = ""
    use_cache: bool = True
    mode: str = "auto"
    programs: Programs = None     # shared with the backends made from this one (with_mode)

    def __post_init__(self):
        if self.programs is None:
            self.programs = Programs(lambda features, tune: build_program(
                self.context, self.device.device, self.extra, self.use_cache, features, tune).program,
                self.device.name, is_nvidia(self.device.device))

    def with_mode(self, mode: str) -> "Backend":
        """The same device, context, queue and programs, choosing among them by `mode`."""
        return Backend(self.device, self.context, self.queue, self.opened, self.extra, self.use_cache, mode,
                       self.programs)

    def generic(self, media: bool) -> cl.Program:
        """The generic program with or without media (Features.generic_program), tuned (on
        NVIDIA under the register caps of app/device/occupancy.py, which the heaviest programs gain
        most from: docs/notes/performance-2026-11.md); waits for it. Refused in one line where
        `pathtrace devices --check` found it rendering wrongly on this device and driver."""
        if generic_refused(self.device.device, self.extra):
            raise UserError(f"{self.device.name}: the generic kernels rendered wrongly on this device and driver "
                            "(pathtrace devices --check); render with --program specialised or auto")
        return self.programs.get(Features.generic_program(media), tuned=True)

    def built_generic(self, media: bool):
        """The generic program with or without media if it is built, else None (the one without
        is built at open where it renders from a cache; `pathtrace devices --check` builds both; neither is
        built behind a scene's first image), and None where that check refused it."""
        if generic_refused(self.device.device, self.extra):
            return None
        return self.programs.built(Features.generic_program(media), tuned=True)

    def refuse_generic(self) -> bool:
        """Marks the generic programs as rendering wrongly on this device and driver (found by
        `pathtrace devices --check`), so that no render uses them: scenes then wait for their
        own program's untuned build. Drops their cached binaries. Whether the mark was made:
        an unwritable cache holds none (nor, then, a generic program that a render would use)."""
        try:
            for media in (False, True):
                generic_entry(self.device.device, self.extra, media).unlink(missing_ok=True)
            mark = generic_entry(self.device.device, self.extra, False).with_suffix(".wrong")
            mark.parent.mkdir(parents=True, exist_ok=True)
            mark.touch()
            return True
        except OSError:
            return False

    def program_for(self, features: Features, tuned: bool = True) -> cl.Program:
        """The kernels specialised to `features` (on NVIDIA with `tuned`, under the register caps
        of app/device/occupancy.py), built once per backend; waits for them."""
        return self.programs.get(features, tuned)

    def ready_program(self, features: Features):
        """The tuned kernels specialised to `features` if they are built, else None, their build
        started in the background."""
        return self.programs.ready(features, tuned=True)


def open_device(device: Device, extra: str = "", use_cache: bool = True, mode: str = None) -> Backend:
    """The device with its queue. Where the generic program without media will render, and
    building it will not compile it afresh (built_before: its binary is in pathtrace's cache, or
    PoCL's cache holds it), or the mode renders with nothing else and PoCL builds it in 2 s on two
    cores, it is built now: it shows that the platform builds the kernels and draws the first
    images of every scene without media (pathtrace.device.programs); the one with media is built
    where a scene asks for it. Elsewhere the display's small program shows that the platform
    builds, and a first image waits for the scene's own program, one build: NVIDIA's driver takes
    minutes over the generic program on an H200 (a build in a background thread held up the
    scene's own build behind it), and PoCL's first build and launch of it take longer than a
    scene's own (cornell-box cold on two cores: 4.1 s to the first image, 3.0 s with its own).
    `pathtrace devices --check` (./install.sh runs it) builds the generic programs."""
    context = new_context(device.device)
    queue = cl.CommandQueue(context, properties=cl.command_queue_properties.PROFILING_ENABLE)
    mode = mode or default_mode()
    source, options, entry = _generic_build(device.device, extra, False, cache_dir())   # most scenes' (the viewer's first)
    cached = built_before(device.device, entry)
    fast = mode != "specialised" and (cached or (mode == "generic" and keeps_own_cache(device.device))) \
        and not generic_refused(device.device, extra)
    if not fast:
        source, options = display_source(), list(BUILD_OPTIONS)
    opened = build_cached(context, device.device, source, options, use_cache, fast)   # tuned: the generic program
    backend = Backend(device, context, queue, opened, extra, use_cache, mode)
    if fast:
        backend.programs.add(Features.generic_program(media=False), True, opened.program)
    return backend


def generic_entry(device: cl.Device, extra: str, media: bool) -> Path:
    """The cache entry of the tuned generic program with or without media (cache_entry)."""
    return _generic_build(device, extra, media, cache_dir())[2]


@functools.lru_cache(maxsize=None)
def _generic_build(device: cl.Device, extra: str, media: bool, folder: Path) -> tuple:
    """The generic program's source, build options and cache entry under cache folder `folder`:
    assembled and hashed once per process, for open_device and for every choice of a program."""
    generic = Features.generic_program(media)
    source, options = kernel_source(extra, generic), program_options(device, generic)
    return source, options, cache_entry(device, source, options, True)


def generic_refused(device: cl.Device, extra: str = "") -> bool:
    """Whether `pathtrace devices --check` found the generic programs rendering wrongly on this
    device and driver (Backend.refuse_generic): a mark beside the one without media's entry. A
    new pathtrace version or driver has entries of its own, without the mark, and the next
    check tests them; deleting the `.wrong` file under the kernel cache tests them again."""
    return generic_entry(device, extra, False).with_suffix(".wrong").is_file()


def display_source() -> str:
    """kernels/display.cl alone: the window's kernel, which needs nothing of the renderer's."""
    return (resource_dir("kernels") / DISPLAY_FILE).read_text()


def check_fits(device: cl.Device, buffers: dict, what: str):
    """Refuses, with one line, buffers (name: bytes) that `device` cannot hold: one larger than its
    largest allocation, or all together more than its global memory."""
    name = device.name.strip()
    largest = max(buffers, key=buffers.get)
    if buffers[largest] > device.max_mem_alloc_size:
        raise UserError(f"{what}: its buffer '{largest}' needs {format_bytes(buffers[largest])}; "
                        f"{name} allocates at most {format_bytes(device.max_mem_alloc_size)} at once")
    total = sum(buffers.values())
    if total > device.global_mem_size:
        raise UserError(f"{what} needs {format_bytes(total)} of device memory; "
                        f"{name} has {format_bytes(device.global_mem_size)}")


def build_error_line(error: Exception) -> str:
    """The compiler's first error line, else the first line of the message."""
    lines = [line.strip() for line in str(error).strip().splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("error")]
    return (errors or lines or [type(error).__name__])[0]


def _index(text: str) -> bool:
    """Whether text is a device index: ASCII digits, few of them (str.isdigit also takes '²',
    which int() refuses, and int() refuses 5000 digits)."""
    return text.isascii() and text.isdigit() and len(text) <= 9


def _matches(spec: str, d: Device, devices: list[Device]) -> bool:
    spec_l = spec.lower()
    kind, _, nth = spec_l.partition(":")
    if kind in ("gpu", "cpu") and _index(nth):       # the nth device of a kind, from 0
        of_kind = [e for e in devices if e.kind.lower() == kind]
        return int(nth) < len(of_kind) and of_kind[int(nth)] is d
    if spec_l in ("auto", "any"):
        return True
    if spec_l in ("gpu", "cpu"):
        return d.kind.lower() == spec_l
    if _index(spec):
        return d.index == int(spec)
    return spec_l in d.name.lower() or spec_l in d.platform.name.lower()


def choose_devices(specs: list[str], log=lambda line: print(line, file=sys.stderr)) -> list[Backend]:
    """Repeated --device options: one backend per spec (a spec named twice opens its device
    twice, as two independent queues), or 'all': every device that builds the kernels."""
    if "all" not in (s.lower() for s in specs):
        return [choose_device(spec, log=log) for spec in specs]
    backends, devices = [], list_devices()
    if not devices:
        raise UserError(no_device())
    for d in devices:
        try:
            backends.append(open_device(d))
        except cl.Error as e:
            log(f"skipping {d.describe()}: cannot build the kernels: {build_error_line(e)}")
    if not backends:
        raise UserError("device all: no OpenCL device can build the kernels "
                        "(see 'pathtrace devices --check')")
    return backends


def choose_device(spec: str = "auto", extra: str = "", use_cache: bool = True,
                  log=lambda line: print(line, file=sys.stderr)) -> Backend:
    """--device: 'auto' (the first GPU whose platform builds our kernels, else a CPU), 'gpu',
    'cpu', 'gpu:N' or 'cpu:N' (the Nth of that kind, from 0), an index from `pathtrace
    devices`, or a fragment of a device or platform name.
    A device whose platform cannot build the kernels is skipped with one line saying why. An
    empty spec is refused (as a fragment of a name it would match every device)."""
    if not spec.strip():
        raise UserError("device: empty; give auto, gpu, cpu, gpu:N, cpu:N, an index from 'pathtrace devices' "
                        "or part of a device's name")
    devices = list_devices()
    if not devices:
        raise UserError(no_device())
    candidates = [d for d in devices if _matches(spec, d, devices)]
    if not candidates:
        found = ", ".join(f"{d.name.strip()} ({d.kind})" for d in devices[:3]) + (", ..." if len(devices) > 3 else "")
        raise UserError(f"device: no OpenCL device matches {short(spec)}; found {found} (see 'pathtrace devices')")
    candidates.sort(key=lambda d: d.kind != "GPU")   # stable: GPUs first, then listing order
    for d in candidates:
        try:
            return open_device(d, extra, use_cache)
        except cl.Error as e:
            log(f"skipping {d.describe()}: cannot build the kernels: {build_error_line(e)}")
    raise UserError(f"device: no device matching {short(spec)} can build the kernels")
