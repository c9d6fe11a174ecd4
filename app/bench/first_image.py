"""`pathtrace bench --first-image`: the seconds from `pathtrace render` to its first image
written, what a user waits for on opening a scene, building the kernels included (`bench --load`
times the same command once they are built). Each row times `python -m pathtrace render SCENE
--size WxH --spp 1 -o OUT.exr` in fresh processes, from process start to exit, Python's start-up
and imports included, and checks that the image was written:

- cold: the median of --repeats runs, each with every cache the render reads empty: a fresh XDG_CACHE_HOME, which holds
  pathtrace's kernel, BVH and scene caches (app/io/cache_files.py cache_dir, app/compiler/bvh_cache.py,
  app/scene/read_cache.py; PATHTRACE_CACHE, PATHTRACE_BVH_CACHE and PATHTRACE_SCENE_CACHE are
  unset), a fresh POCL_CACHE_DIR (PoCL's cache of the programs it
  built, which pathtrace relies on there in place of its own) and a fresh CUDA_CACHE_PATH (the
  NVIDIA driver's cache of compiled kernels): a first start, whose time varies by a few tenths
  of a second from run to run on a GPU's host (docs/benchmarks.md), so one run is not its figure;
- warm: the same command with the same folders, which the last cold run filled, the best of
  --repeats: a scene opened again;
- edited: the same again, before each run the scene file's time of last change moved on by a
  second, so that its entry in the scene cache no longer holds: a scene opened again after an
  edit of its file, read again but for its OBJ files' meshes, which come from beside the entry
  (app/scene/mesh_cache.py; a PLY file is read again), the best of --repeats; for the files
  bench writes alone, not a user's.

The rows: --scenes (by default pathtrace.bench.default_scenes.FIRST_IMAGE_SCENES): built-in scenes, `meshes850`
(850 PLY tori in a Mitsuba XML file, pathtrace.bench.scenes.write_meshes) and the files `pathtrace
bench` writes (pathtrace.bench.default_scenes.GENERATED_FILES), each written with the rows' size; then
each --load-scene file.
With --mitsuba PYTHON, Mitsuba 3 loads and renders with 1 spp the row's XML (the scene's own file,
or a twin written for a built-in one: pathtrace.bench.report.mitsuba_twin) in a fresh process of that
Python (pathtrace.bench.mitsuba_timing), cold and then warm in the same way: Dr.Jit keeps its kernels
in ~/.drjit and CUDA in ~/.nv, so Mitsuba runs with a fresh HOME (Python's user site kept through
PYTHONUSERBASE). Mitsuba renders an XML file as it is, so a file whose film is not the rows' size
gets no Mitsuba column, and a line says so."""

import os
import shutil
import site
import statistics
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from pathtrace.bench.default_scenes import FIRST_IMAGE_SCENES, GENERATED_FILES
from pathtrace.bench.report import mitsuba_twin, scene_file
from pathtrace.bench.scenes import write_meshes
from pathtrace.device.driver_caches import for_children
from pathtrace.errors import UserError
from pathtrace.io.files import shown
from pathtrace.bench.load import best_time, cache_bytecode, run_times
from pathtrace.bench.mitsuba_timing import mitsuba_load_command
from pathtrace.scene import load_scene

MESHES = "meshes850"
SIZE = (640, 360)
# the variables that would point pathtrace at caches other than the fresh folders
PATHTRACE_CACHES = ("PATHTRACE_CACHE", "PATHTRACE_BVH_CACHE", "PATHTRACE_SCENE_CACHE")


@dataclass
class FirstImage:
    scene: str
    what: str                   # the scene in words
    device: str                 # pathtrace's --device
    width: int
    height: int
    cold_seconds: float         # command to image, every cache empty: the median of the repeats
    warm_seconds: float         # the same with the caches the cold runs filled, best of the repeats
    cache_folder: str           # the cold run's caches (removed after the bench)
    cache_files_before: int     # files in it before the cold run
    cache_files_after: int      # and after it
    edited_seconds: float = None    # the same after the scene's file changed (the files bench writes)
    mitsuba_variant: str = ""
    mitsuba_cold_seconds: float = None
    mitsuba_warm_seconds: float = None
    cold_runs: list = None      # each cold run's seconds, pathtrace's and Mitsuba's
    mitsuba_cold_runs: list = None


def validate(args):
    """The mode's defaults into args (--scenes, --size), and each scene loaded, so that a bad
    name or file fails in one line before any timed run."""
    args.scenes = args.scenes or list(FIRST_IMAGE_SCENES)
    args.size = args.size or SIZE
    for name in args.scenes:
        if name not in (MESHES, *GENERATED_FILES):
            load_scene(name)
    for name in args.load_scene or []:
        load_scene(name)


def cache_env(caches: Path) -> dict:
    """The environment of a render whose caches all lie in `caches` (not PyOpenCL's cache turned
    off where this process's could not be written: pathtrace.device.driver_caches)."""
    env = {k: v for k, v in for_children(dict(os.environ)).items() if k not in PATHTRACE_CACHES}
    return {**env, "XDG_CACHE_HOME": str(caches / "xdg"), "POCL_CACHE_DIR": str(caches / "pocl"),
            "CUDA_CACHE_PATH": str(caches / "nv")}


def mitsuba_env(home: Path) -> dict:
    """The environment of a Mitsuba process whose kernel caches lie in `home`."""
    return {**os.environ, "HOME": str(home), "CUDA_CACHE_PATH": str(home / ".nv" / "ComputeCache"),
            "PYTHONUSERBASE": os.environ.get("PYTHONUSERBASE") or site.getuserbase()}


def files_in(folder: Path) -> int:
    return sum(1 for f in folder.rglob("*") if f.is_file()) if folder.exists() else 0


def rows(folder: Path, scenes, scene_files, size) -> list:
    """(name, the scene as `render` takes it, the scene in words) for each row."""
    found = []
    named_files = [name for name in scenes if Path(name).is_file()]     # a file named by --scenes too
    scene_files = [*named_files, *scene_files]
    for name in (name for name in scenes if name not in named_files):
        if name == MESHES:
            where = folder / MESHES
            where.mkdir()
            _, xml, what, _ = write_meshes(where, size=size)
            found.append((name, str(where / xml), what))
        else:
            found.append((name, scene_file(name, folder, size),
                          "written by bench" if name in GENERATED_FILES else "built-in"))
    for f in scene_files:
        path = Path(f).resolve()
        found.append((path.stem, str(path), "/".join(path.parts[-3:])[-34:]))
    return found


def run(device: str, scenes, scene_files, size: tuple, repeats: int, mitsuba_python: str = None,
        variant: str = "llvm_ad_rgb", log=print) -> list[FirstImage]:
    """A row per scene of `scenes` (built-in names, MESHES, GENERATED_FILES), then per file of
    scene_files, rendered on `device` (a --device spec)."""
    folder = Path(tempfile.mkdtemp(prefix="pathtrace-first-image-"))
    out = folder / "out.exr"
    results = []
    cache_bytecode()
    try:
        for k, (name, scene, what) in enumerate(rows(folder, scenes, scene_files, size)):
            render = [sys.executable, "-m", "pathtrace", "render", scene, "--size", f"{size[0]}x{size[1]}",
                      "--spp", "1", "--device", device, "-o", str(out), "-q"]
            caches = folder / f"caches{k}"
            env = cache_env(caches)
            before = files_in(caches)
            cold = run_times(render, repeats, folder, env, out, lambda: shutil.rmtree(caches, ignore_errors=True))
            r = FirstImage(name, what, device, *size, statistics.median(cold),
                           best_time(render, repeats, folder, env, out), str(caches), before, files_in(caches),
                           cold_runs=cold)
            if name in (MESHES, *GENERATED_FILES):
                r.edited_seconds = min(run_times(render, repeats, folder, env, out, lambda: _edited(Path(scene))))
            note = time_mitsuba(r, scene, folder / f"mitsuba{k}", mitsuba_python, variant, repeats) \
                if mitsuba_python else ""
            log(format_row(r))
            if note:
                log(f"{'':<16} Mitsuba 3: {note}")
            results.append(r)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return results


def time_mitsuba(r: FirstImage, scene_name: str, folder: Path, python: str, variant: str, repeats: int) -> str:
    """Mitsuba's cold and warm seconds from command to image for the row's scene, into r; where
    it has no XML of the row's size, why not."""
    folder.mkdir()
    scene = load_scene(scene_name)
    source = str(scene.source or "")
    film = scene.settings.width, scene.settings.height
    if source.lower().endswith(".xml") and film != (r.width, r.height):
        return (f"{shown(Path(source).name)} has a {film[0]}x{film[1]} film, which Mitsuba renders as it is; "
                f"--size {film[0]}x{film[1]} compares it")
    try:
        xml = mitsuba_twin(scene, (r.width, r.height), 1, folder)
    except UserError as e:        # the scene says what a twin cannot: no column
        return f"no twin of {r.scene}: {e}"
    out = folder / "mitsuba.exr"
    command = mitsuba_load_command(python, variant, xml, out)
    env = mitsuba_env(folder / "home")
    r.mitsuba_variant = variant
    r.mitsuba_cold_runs = run_times(command, repeats, folder, env, out,
                                    lambda: shutil.rmtree(env["HOME"], ignore_errors=True))
    r.mitsuba_cold_seconds = statistics.median(r.mitsuba_cold_runs)
    r.mitsuba_warm_seconds = best_time(command, repeats, folder, env, out)
    return ""


def _edited(path: Path):
    """The file's time of last change moved on by a second, as an editor's saving would."""
    info = path.stat()
    os.utime(path, ns=(info.st_atime_ns, info.st_mtime_ns + 10**9))


HEADER = (f"{'scene':<16} {'what':<34} {'device':<8} {'size':>9} {'cold s':>7} {'warm s':>7} {'edited s':>8} "
          f"{'Mitsuba 3 cold/warm s':>34} {'ratio cold/warm':>15}")


def format_row(r: FirstImage) -> str:
    """The row; the ratio is Mitsuba's seconds over pathtrace's (above 1: pathtrace's image first)."""
    theirs = ratio = "-"
    if r.mitsuba_cold_seconds is not None:
        theirs = f"{r.mitsuba_cold_seconds:.2f}/{r.mitsuba_warm_seconds:.2f} ({r.mitsuba_variant})"
        ratio = f"{r.mitsuba_cold_seconds / r.cold_seconds:.2f}/{r.mitsuba_warm_seconds / r.warm_seconds:.2f}"
    edited = "-" if r.edited_seconds is None else f"{r.edited_seconds:.2f}"
    return (f"{r.scene:<16} {r.what:<34} {r.device:<8} {f'{r.width}x{r.height}':>9} {r.cold_seconds:>7.2f} "
            f"{r.warm_seconds:>7.2f} {edited:>8} {theirs:>34} {ratio:>15}")
