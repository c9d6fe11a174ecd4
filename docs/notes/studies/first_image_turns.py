"""Two versions of pathtrace timed in turns, as a user waits: `render SCENE --size 640x360 --spp 1`
from the command to its exit, warm (each version's own kernel caches filled by a first, untimed
render that prints its phase lines) and cold (every cache emptied before each render). A version is
a PYTHONPATH under which `import pathtrace` is that tree, e.g. a `git archive` of the commit
before a change with `pathtrace` linked to its app/ (docs/notes/performance-2026-12.md,
twenty-third session: the host's trees):

    python docs/notes/studies/first_image_turns.py --device gpu --warm 10 --cold 8 \\
        --version base=/tmp/base/pp --version new=/tmp/new/pp cornell-box teapot-sky

The first scene is timed cold as well. Prints each render's seconds and the medians."""

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time


def render(pythonpath: str, caches: str, scene: str, device: str, cold: bool, show: bool) -> float:
    if cold:
        shutil.rmtree(caches, ignore_errors=True)
    env = dict(os.environ, PYTHONPATH=pythonpath, XDG_CACHE_HOME=caches, CUDA_CACHE_PATH=f"{caches}/cuda",
               POCL_CACHE_DIR=f"{caches}/pocl")
    out = caches + "-out.png"
    command = [sys.executable, "-m", "pathtrace", "render", scene, "--device", device, "--size", "640x360",
               "--spp", "1", "-o", out] + ([] if show else ["-q"])
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode or show:
        print(done.stderr[-1500:], file=sys.stderr)
    if done.returncode:
        raise SystemExit(f"{scene}: the render failed")
    return seconds


def in_turns(versions: dict, folder: str, scene: str, device: str, runs: int, cold: bool):
    times = {name: [] for name in versions}
    for i in range(runs):
        order = list(versions) if i % 2 == 0 else list(reversed(versions))
        for name in order:
            caches = os.path.join(folder, name + ("-cold" if cold else ""))
            times[name].append(render(versions[name], caches, scene, device, cold, cold and i == 0))
    for name, seconds in times.items():
        print(f"{'cold' if cold else 'warm'} {scene} {name}: {' '.join(f'{s:.3f}' for s in seconds)} "
              f"median {statistics.median(seconds):.3f}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("scenes", nargs="+")
    parser.add_argument("--version", action="append", required=True, help="NAME=PYTHONPATH")
    parser.add_argument("--device", default="auto")
    parser.add_argument("--warm", type=int, default=10)
    parser.add_argument("--cold", type=int, default=5)
    args = parser.parse_args()
    versions = dict(v.split("=", 1) for v in args.version)
    with tempfile.TemporaryDirectory() as folder:
        for scene in args.scenes:
            for name, pythonpath in versions.items():       # each version's caches filled
                render(pythonpath, os.path.join(folder, name), scene, args.device, False, True)
            in_turns(versions, folder, scene, args.device, args.warm, False)
        in_turns(versions, folder, args.scenes[0], args.device, args.cold, True)


if __name__ == "__main__":
    main()
