"""A field of instances of one 100,000-triangle object (a million by default: 1e11 triangles
drawn), compiled into a two-level BVH and rendered at 1920x1080 with NEE: the scale that
docs/scene-format.md's Instances section promises (docs/notes/performance-2026-11.md has the H100's figures).

    python docs/notes/studies/many_instances.py [instances] [device] [small]

`small` renders 64x36 at 4 spp instead (for a CPU)."""

import sys
import time

import numpy as np

from pathtrace.cameras import PerspectiveCamera
from pathtrace.device.opencl import choose_device
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import Mesh, SceneBuilder, diffuse

TRIANGLES = 100_000


def field_of_bushes(count: int):
    """A floor, and `count` instances of a bush of TRIANGLES small triangles on a square grid."""
    rng = np.random.default_rng(1)
    b = SceneBuilder()
    floor = np.array([[-2000, 0, -2000], [2000, 0, -2000], [2000, 0, 2000], [-2000, 0, 2000]], np.float32)
    b.add_mesh(Mesh("floor", floor, np.array([[0, 2, 1], [0, 3, 2]], np.int32), None, b.material(diffuse(0.5))))
    bush = b.add_object("bush")
    centres = rng.normal(size=(TRIANGLES, 1, 3)) + [0, 2, 0]
    corners = (centres + rng.normal(scale=0.08, size=(TRIANGLES, 3, 3))).astype(np.float32)
    b.objects[bush].meshes.append(Mesh("bush", corners.reshape(-1, 3),
                                       np.arange(3 * TRIANGLES, dtype=np.int32).reshape(-1, 3), None,
                                       b.material(diffuse((0.7, 0.6, 0.5)))))
    side = int(np.ceil(np.sqrt(count)))
    for i in range(count):
        t = np.eye(4)
        t[0, 3], t[2, 3] = (i % side - side / 2) * 4.0, (i // side - side / 2) * 4.0
        b.add_instance(bush, t)
    return b.build("bushes", camera=PerspectiveCamera(eye=np.array([0.0, 60.0, -200.0]), look_at=np.zeros(3), vfov=40.0))


def main(argv):
    count = int(argv[0]) if argv else 1_000_000
    device = choose_device(argv[1] if len(argv) > 1 else "gpu")
    width, height, spp = (64, 36, 4) if len(argv) > 2 else (1920, 1080, 64)
    t0 = time.perf_counter()
    scene = field_of_bushes(count).with_settings(max_depth=8, russian_roulette="off", nee=True)
    t1 = time.perf_counter()
    r = Renderer(device, scene, width, height)
    t2 = time.perf_counter()
    r.add_samples(4)
    r.finish()
    t3 = time.perf_counter()
    r.add_samples(spp)
    r.finish()
    t4 = time.perf_counter()
    c = r.compiled
    geometry = sum(a.nbytes for a in c.geometry_arrays().values()) / 2 ** 20
    print(f"{count} instances of {TRIANGLES} triangles ({scene.instances.triangle_count:.3g} drawn): scene built in "
          f"{t1 - t0:.2f} s, compiled and uploaded in {t2 - t1:.2f} s (BVH {c.bvh_seconds:.2f} s), first 4 spp "
          f"{t3 - t2:.2f} s, {spp} spp at {width}x{height} {t4 - t3:.3f} s; geometry {geometry:.0f} MiB; "
          f"mean {r.mean().mean():.4f}")


if __name__ == "__main__":
    main(sys.argv[1:])
