"""BDPT's time per sample on Bitterli's scenes (docs/notes/performance-2026-11.md, 2026-11-30,
tenth session: the splats' atomics, before and after, on the H200 and on two cores). Each scene's
pbrt-v4 file from $BITTERLI (SCENE/pbrt/scene-v4.pbrt, as ../shared/scenes unpacks), rendered by
BDPT without caustic photons after a first sample (whose time holds the program's build); the
best over ROUNDS of LAUNCHES launches of PER samples each, in ns per sample.
python docs/notes/studies/bdpt_sample_time.py DEVICE SIZE LAUNCHES PER ROUNDS SCENE...
  H200:     python docs/notes/studies/bdpt_sample_time.py gpu 512 16 1 2 veach-bidir water-caustic
  two cores: python docs/notes/studies/bdpt_sample_time.py cpu 96 1 4 5 veach-bidir"""
import os
import sys
import time

from pathtrace.device.opencl import choose_device
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene

device, size, launches, per, rounds = sys.argv[1], *map(int, sys.argv[2:6])
backend = choose_device(device)
for name in sys.argv[6:]:
    scene = load_scene(f"{os.environ.get('BITTERLI', '.')}/{name}/pbrt/scene-v4.pbrt")
    r = Renderer(backend, scene.with_settings(integrator="bdpt", photon_radius=0.0, seed=1), size, size)
    r.add_samples(1)
    r.finish()
    best = float("inf")
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(launches):
            r.add_samples(per)
        r.finish()
        best = min(best, (time.perf_counter() - start) / (launches * per * size * size))
    print(f"{name} {size}x{size} on {backend.device.name}: {best * 1e9:.1f} ns per sample", flush=True)
