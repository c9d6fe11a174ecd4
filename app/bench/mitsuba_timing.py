"""Mitsuba 3 timed beside pathtrace, in a fresh process of a Python that has it (`pathtrace bench
--mitsuba PYTHON`): pathtrace does not depend on Mitsuba, and a process of its own keeps Dr.Jit's
threads and GPU context out of ours. Two measurements:

- load: `mitsuba.load_file` and a 1-spp render of an XML file, timed from process start to exit;
- render: the scene loaded, its camera replaced by pathtrace's view of it (eye, target, up,
  vertical fov, the film's size, a box filter) and its integrator by `path` at the row's max
  depth without Russian roulette (rr_depth beyond it, as pathtrace's comparison mode), one
  untimed render of all the samples, then another (in as many passes as Mitsuba chooses for its
  memory), timed to the end of its evaluation, or `rounds` more, each timed (`bench --rounds`).
  The untimed render has the timed ones' samples because Dr.Jit's kernels may depend on the
  sample count (Mitsuba 3.9.1's log for its Cornell box: 1 and 2 spp shared a kernel, 16 and 32
  another, 24 and 48 a third, each compiled at its first use, 0.37 s on two cores), and because
  a render's wavefront memory, which Dr.Jit keeps for the next, grows with it: neither belongs in
  the timed render, as pathtrace's kernels and buffers are made before its own. The image's
  mean comes back with the seconds, so that a twin that differs from pathtrace's scene shows."""

import json
import os
import subprocess

from pathtrace.errors import UserError

LOAD = """
import sys, mitsuba as mi
mi.set_variant(sys.argv[2])
mi.Bitmap(mi.render(mi.load_file(sys.argv[1]), spp=1)).write(sys.argv[3])
"""
RENDER = """
import json, sys, time
import drjit as dr, mitsuba as mi, numpy as np
a = json.loads(sys.argv[1])
mi.set_variant(a["variant"])
scene = mi.load_file(a["xml"])
sensor = mi.load_dict({
    "type": "perspective", "fov": a["vfov"], "fov_axis": "y",
    "to_world": mi.ScalarTransform4f().look_at(origin=a["eye"], target=a["target"], up=a["up"]),
    "film": {"type": "hdrfilm", "width": a["width"], "height": a["height"], "rfilter": {"type": "box"},
             "pixel_format": "rgb"},
    "sampler": {"type": "independent", "sample_count": 1}})
integrator = mi.load_dict({"type": "path", "max_depth": a["max_depth"], "rr_depth": a["max_depth"] + 1})
image = mi.render(scene, sensor=sensor, integrator=integrator, spp=a["spp"], seed=0)
dr.eval(image); dr.sync_thread()
seconds = []
for seed in range(1, a["rounds"] + 1):
    start = time.perf_counter()
    image = mi.render(scene, sensor=sensor, integrator=integrator, spp=a["spp"], seed=seed)
    dr.eval(image); dr.sync_thread()
    seconds.append(time.perf_counter() - start)
print(json.dumps({"seconds": seconds, "mean": float(np.mean(np.array(image)[..., :3]))}))
"""


def run_command(command, cwd=None, env=None):
    """subprocess.run, its output captured; a program that cannot be run is one line."""
    try:
        return subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True)
    except OSError as e:          # a Python that is not there, or not a program
        raise UserError(f"bench: cannot run {command[0]}: {e.strerror or e}") from None


def check_mitsuba(python: str, variant: str):
    """Refuses, in one line and before any timed run, a Python that cannot run Mitsuba 3's
    `variant` (no Mitsuba there, or a variant its machine lacks: LLVM, CUDA)."""
    r = run_command([python, "-c", "import sys, mitsuba as mi; mi.set_variant(sys.argv[1])", variant])
    if r.returncode:
        raise UserError(f"bench: --mitsuba {python} cannot run Mitsuba 3's {variant}: {last_line(r)}")


def last_line(r) -> str:
    """The last line a finished command wrote, to name its failure."""
    return (r.stderr.strip().splitlines() or r.stdout.strip().splitlines() or ["(no output)"])[-1]


def mitsuba_load_command(python: str, variant: str, xml, out) -> list:
    """The command of the load measurement; a relative path to the Python made absolute, as the
    benchmarks run it from a folder of their own."""
    return [os.path.abspath(python) if os.sep in python else python, "-c", LOAD, str(xml), variant, str(out)]


def mitsuba_render(python: str, variant: str, xml, camera, width: int, height: int, spp: int,
                   max_depth: int, rounds: int = 1) -> tuple[list, float]:
    """Mitsuba's seconds to render `xml` as described above, one per timed round, and its last
    image's mean."""
    args = dict(variant=variant, xml=str(xml), width=width, height=height, spp=spp, max_depth=max_depth,
                rounds=rounds, eye=[float(x) for x in camera.eye], target=[float(x) for x in camera.look_at],
                up=[float(x) for x in camera.up], vfov=float(camera.vfov))
    r = run_command([python, "-c", RENDER, json.dumps(args)])
    if r.returncode:
        raise UserError(f"bench --mitsuba: Mitsuba 3 ({python}, {variant}) failed on {xml}: {last_line(r)}")
    result = json.loads([line for line in r.stdout.splitlines() if line.startswith("{")][-1])
    return result["seconds"], result["mean"]
