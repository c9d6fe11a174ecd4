"""The viewer's first image, timed as a user waits for it (docs/notes/performance-2026-11.md,
2026-11-30, fifteenth session): `pathtrace view SCENE` from its process's start to its line
"first image of SCENE in S s" (app/viewer/opening.py: say_first_image), then ended. Per scene:
once with its own scene and BVH caches empty (a new scene; the kernel caches as the environment
gives them), then the best of three with them filled. Needs a display (DISPLAY, e.g. Xvfb):

    XDG_CACHE_HOME=... POCL_CACHE_DIR=... pathtrace devices --check     # the generic programs
    python docs/notes/studies/viewer_first_image.py simple cornell-box teapot-sky scene.xml
"""

import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def first_image(scene: str, env: dict) -> float:
    start = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-m", "pathtrace", "view", scene], env=env, stderr=subprocess.PIPE, text=True)
    seconds = None
    for line in p.stderr:
        if line.startswith("first image"):
            seconds = time.perf_counter() - start
            break
    p.send_signal(signal.SIGTERM)
    try:
        p.wait(60)
    except subprocess.TimeoutExpired:
        p.kill()
    if seconds is None:
        raise SystemExit(f"{scene}: the viewer ended without a first image")
    return seconds


def main(scenes):
    for scene in scenes:
        with tempfile.TemporaryDirectory() as caches:
            env = {**os.environ, "PATHTRACE_SCENE_CACHE": str(Path(caches) / "scenes"),
                   "PATHTRACE_BVH_CACHE": str(Path(caches) / "bvh")}
            new = first_image(scene, env)
            warm = min(first_image(scene, env) for _ in range(3))
        print(f"{Path(scene).name:24s} new scene {new:.2f} s, opened again {warm:.2f} s", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
