"""How the BVH builder's settings change `tori400-textured`'s tree (docs/notes/performance-2026-11.md,
2026-11-26): the SAH cost, the time to compile the scene and the nodes and primitives a ray
meets (pathtrace.bench.traversal_stats), for PLOC's search radius, the top split's bins and the
clusters it takes (app/compiler/bvh.py: RADIUS, MAX_BINS, TOP_CLUSTERS); then with its ground quad (two
triangles the size of the scene) left out or made a grid of smaller ones.

    python docs/notes/studies/bvh_settings_study.py [--device D] [--size WxH] [--spp N]
"""

import argparse
import os
import re
import tempfile
import time
from pathlib import Path

import numpy as np

import pathtrace.compiler.bvh as bvh
from pathtrace.bench.report import estimator_settings
from pathtrace.bench.scenes import write_textured_tori
from pathtrace.compiler.compiled import compile_scene
from pathtrace.device.opencl import choose_device
from pathtrace.scene import load_scene
from pathtrace.scene.mitsuba_writer import ply_bytes
from pathtrace.bench.traversal_stats import traversal_stats

SETTINGS = [   # (TOP_CLUSTERS, RADIUS, MAX_BINS); the first is app/compiler/bvh.py's
    (bvh.TOP_CLUSTERS, bvh.RADIUS, bvh.MAX_BINS), (65536, 16, 16), (65536, 8, 32), (262144, 8, 16), (1 << 30, 8, 16)]


def ground_grid(folder: Path, rect: str, n: int, side: int = 20) -> str:
    """The tori's ground rectangle (app/bench/scenes.py) as a PLY grid of n x n quads with the
    same corners, uvs and material: the same surface, in smaller triangles."""
    extent, middle = side * 2.5 + 2, side * 1.25 - 1.25
    u = np.linspace(0, 1, n + 1)
    U, V = np.meshgrid(u, u, indexing="ij")
    points = np.stack([middle + (U * 2 - 1) * extent / 2, np.zeros_like(U), middle - (V * 2 - 1) * extent / 2], -1)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a, b = i * (n + 1) + j, (i + 1) * (n + 1) + j
    faces = np.concatenate([np.stack([a, b, a + 1], -1).reshape(-1, 3), np.stack([b, b + 1, a + 1], -1).reshape(-1, 3)])
    normals = np.tile([0.0, 1.0, 0.0], ((n + 1) ** 2, 1))
    (folder / f"ground{n}.ply").write_bytes(ply_bytes(points.reshape(-1, 3), faces, normals,
                                                      np.stack([U, V], -1).reshape(-1, 2)))
    bsdf = rect[rect.index("<bsdf"):rect.index("</bsdf>") + len("</bsdf>")]
    return f'<shape type="ply"><string name="filename" value="ground{n}.ply"/>{bsdf}</shape>'


def row(what, backend, scene, width, height, spp):
    scene = scene.with_settings(**estimator_settings("depth8+nee"))
    start = time.perf_counter()
    compiled = compile_scene(scene, backend.queue)
    seconds = time.perf_counter() - start
    s = traversal_stats(backend, compiled, width, height, spp)
    print(f"{what:<40} SAH cost {compiled.bvh.cost:6.2f}  compile {seconds:5.2f} s  "
          f"rays/sample {s.rays_per_sample:.2f}  nodes/ray {s.nodes_per_ray:5.2f}  prims/ray {s.primitives_per_ray:.2f}",
          flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--size", default="240x135")
    parser.add_argument("--spp", type=int, default=4)
    args = parser.parse_args()
    os.environ["PATHTRACE_BVH_CACHE"] = "0"       # each row builds its tree (pathtrace.compiler.bvh_cache)
    width, height = map(int, args.size.split("x"))
    backend = choose_device(args.device)
    print(backend.device.describe())
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        xml = write_textured_tori(folder)
        for top, radius, bins in SETTINGS:
            bvh.TOP_CLUSTERS, bvh.RADIUS, bvh.MAX_BINS = top, radius, bins
            row(f"top clusters {min(top, 410_000)}, radius {radius}, bins {bins}", backend, load_scene(str(xml)),
                width, height, args.spp)
        bvh.TOP_CLUSTERS, bvh.RADIUS, bvh.MAX_BINS = SETTINGS[0]
        text = xml.read_text()
        rect = re.search(r'<shape type="rectangle">.*?</shape>', text, re.S).group(0)
        variants = [("no ground", "")] + [(f"ground as {2 * n * n} triangles", ground_grid(folder, rect, n))
                                          for n in (1, 8, 32, 128)]
        for what, ground in variants:
            path = folder / "variant.xml"
            path.write_text(text.replace(rect, ground))
            row(what, backend, load_scene(str(path)), width, height, args.spp)


if __name__ == "__main__":
    main()
