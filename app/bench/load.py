"""`pathtrace bench --load`: the seconds from a command to its first image, what a user waits
for before anything else. Each row writes a scene's files (pathtrace.bench.scenes:
heightfield1M and meshes850) or takes a scene file given, and times `pathtrace render FILE` at
64x64 (64x36 for the height field) with 1 spp from process start to exit, Python's start-up and
imports included, best of --repeats after one untimed run that fills the kernel cache: with the
BVH built (the BVH cache turned off), then with the BVH read from the cache that run filled
(pathtrace.compiler.bvh_cache), as a scene opened a second time loads. With --mitsuba PYTHON the same
scene's Mitsuba 3 XML is loaded and rendered with 1 spp in a fresh process of that Python, timed
the same way, in the same run (pathtrace.bench.mitsuba_timing); the ratio is against the build."""

import os
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from pathtrace.bench.scenes import write_height_field, write_meshes
from pathtrace.errors import UserError, did_you_mean, short
from pathtrace.io.files import shown
from pathtrace.bench.mitsuba_timing import last_line, mitsuba_load_command, run_command


@dataclass
class LoadTime:
    scene: str
    what: str                   # its size in words
    device: str                 # pathtrace's --device
    seconds: float              # pathtrace, command to image, the best of the repeats
    cached_seconds: float       # the same, the scene and its BVH read from their caches
    mitsuba_variant: str = ""
    mitsuba_seconds: float = None


# the packages a render imports besides pathtrace, whose bytecode an installation holds
RENDER_IMPORTS = ("numpy", "pyopencl", "pytools", "platformdirs", "tqdm", "PIL", "OpenEXR", "plyfile")


def cache_bytecode():
    """Writes the bytecode of the package and of the packages a render imports where it can, as
    an installation does, so that the timed processes read it rather than compile every module
    (pathtrace's: 0.11 s of a command's start on two cores; NumPy's, on a lent H200 machine whose
    packages were installed without it: 0.36 s), also where PYTHONDONTWRITEBYTECODE keeps them
    from writing it: they time what a user waits for. A folder that cannot be written is left as
    it is, and a package not installed is passed over."""
    import compileall
    import importlib.util
    folders = [str(Path(__file__).resolve().parent.parent)]
    for name in RENDER_IMPORTS:
        try:
            spec = importlib.util.find_spec(name)
        except (ImportError, ValueError):
            continue
        if spec is not None and spec.submodule_search_locations:
            folders += list(spec.submodule_search_locations)
    for folder in folders:
        compileall.compile_dir(folder, quiet=2)


def best_time(command, repeats: int, cwd, env=None, output: Path = None) -> float:
    """The shortest of `repeats` runs of `command` (run_times)."""
    return min(run_times(command, repeats, cwd, env, output))


def run_times(command, repeats: int, cwd, env=None, output: Path = None, before=None) -> list:
    """The seconds of `repeats` runs of `command`, each from process start to exit; a failure is
    one line naming the command and its last line of output. output: the image the command writes,
    removed before each run; a run that leaves none fails too. before(): called before each run
    (a cold run's caches emptied)."""
    times = []
    for _ in range(repeats):
        if output is not None:
            output.unlink(missing_ok=True)
        if before is not None:
            before()
        start = time.perf_counter()
        r = run_command(command, cwd, env)
        times.append(time.perf_counter() - start)
        if r.returncode:
            raise UserError(f"bench: {command_line(command)} failed: {last_line(r)}")
        if output is not None and not (output.is_file() and output.stat().st_size):
            raise UserError(f"bench: {command_line(command)} exited 0 but wrote no {shown(output.name)}")
    return times


def command_line(command, words: int = 7) -> str:
    """The start of a command, on one line: its first `words` words, a script given with -c
    (Mitsuba's, pathtrace.bench.mitsuba_timing) as '...'."""
    shown_words = ["..." if k and str(command[k - 1]) == "-c" else shown(word) for k, word in enumerate(command)]
    return " ".join(shown_words[:words]) + (" ..." if len(command) > words else "")


GENERATED_ROWS = {"heightfield1M": write_height_field, "meshes850": write_meshes}


def check_rows(names) -> list:
    """--scenes with --load: `names` where each is one of GENERATED_ROWS, else one line."""
    for name in names:
        if name not in GENERATED_ROWS:
            raise UserError(f"--scenes: with --load, {short(name)} is not a generated row (one of "
                            f"{', '.join(GENERATED_ROWS)}){did_you_mean(name, GENERATED_ROWS)}")
    return list(names)


def run_load(device: str, scene_files, repeats: int, mitsuba_python: str = None,
             variant: str = "llvm_ad_rgb", log=print, generated=tuple(GENERATED_ROWS)) -> list[LoadTime]:
    """The generated rows named in `generated`, then one per file of scene_files (Mitsuba's
    column for XML files)."""
    folder = Path(tempfile.mkdtemp(prefix="pathtrace-load-"))
    results = []
    cache_bytecode()
    try:
        rows = [GENERATED_ROWS[name](folder) for name in generated]
        rows += [(str(Path(f).resolve()), str(Path(f).resolve()) if f.lower().endswith(".xml") else None,
                  "/".join(Path(f).resolve().parts[-3:])[-36:], (64, 64)) for f in scene_files]
        built = {**os.environ, "PATHTRACE_BVH_CACHE": "0", "PATHTRACE_SCENE_CACHE": "0"}
        cached = {**os.environ, "PATHTRACE_BVH_CACHE": str(folder / "bvh"), "PATHTRACE_SCENE_CACHE": str(folder / "scenes")}
        for scene, xml, what, size in rows:
            render = [sys.executable, "-m", "pathtrace", "render", scene, "--size", f"{size[0]}x{size[1]}",
                      "--spp", "1", "--device", device, "-o", str(folder / "out.exr"), "-q"]
            best_time(render, 1, folder, cached)            # fills the kernel, BVH and scene caches
            r = LoadTime(Path(scene).stem, what, device, best_time(render, repeats, folder, built),
                         best_time(render, repeats, folder, cached))
            if mitsuba_python and xml:
                mitsuba = mitsuba_load_command(mitsuba_python, variant, xml, folder / "mitsuba.exr")
                r.mitsuba_variant, r.mitsuba_seconds = variant, best_time(mitsuba, repeats, folder)
            log(format_load_row(r))
            results.append(r)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return results


LOAD_HEADER = (f"{'scene':<16} {'what':<36} {'device':<8} {'pathtrace s':>11} {'cached s':>12} "
               f"{'Mitsuba 3 s':>22} {'ratio':>6}")


def format_load_row(r: LoadTime) -> str:
    theirs = f"{r.mitsuba_seconds:.2f} ({r.mitsuba_variant})" if r.mitsuba_seconds is not None else "-"
    ratio = f"{r.mitsuba_seconds / r.seconds:.2f}" if r.mitsuba_seconds is not None else "-"
    return (f"{r.scene:<16} {r.what:<36} {r.device:<8} {r.seconds:>11.2f} {r.cached_seconds:>12.2f} "
            f"{theirs:>22} {ratio:>6}")
