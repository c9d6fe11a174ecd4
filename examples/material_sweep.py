"""A material sweep: one scene written in Python, a rough metal's roughness changed between
renders (the scene is compiled once), the images tiled into one grid image.

    python examples/material_sweep.py -o sweep.png [--size 240x180] [--spp 64] [--device auto]
"""

import argparse
import sys

import numpy as np

import pathtrace
from pathtrace.cli.options import image_size

ALPHAS = (0.02, 0.08, 0.2, 0.4, 0.7)         # GGX roughness, smooth to rough

SCENE = {
    "camera": {"eye": [0, 1.2, 4.2], "look_at": [0, 0.7, 0], "vfov": 32},
    "environment": {"map": "studio_small_03_1k.hdr", "intensity": 0.6},     # a map pathtrace ships
    "materials": {
        "metal": {"type": "roughconductor", "material": "Au", "alpha": ALPHAS[0]},
        "floor": {"type": "diffuse", "rho_d": [0.35, 0.35, 0.35]},
    },
    "spheres": [{"center": [0, 0.8, 0], "radius": 0.8, "material": "metal", "name": "ball"}],
    "meshes": [{"name": "floor", "material": "floor",
                "vertices": [[-20, 0, -20], [-20, 0, 20], [20, 0, 20], [20, 0, -20]],
                "faces": [[0, 1, 2], [0, 2, 3]]}],
}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])   # the first paragraph, whole
    parser.add_argument("-o", "--output", default="sweep.png")
    parser.add_argument("--size", default="240x180", type=image_size, help="WxH")
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--device", default="auto")
    args = parser.parse_args()
    width, height = args.size

    scene = pathtrace.load_dict(SCENE, "sweep")
    tiles = []
    for alpha in ALPHAS:
        scene.materials["metal"] = pathtrace.material({"type": "roughconductor", "material": "Au", "alpha": alpha})
        tiles.append(pathtrace.render(scene, spp=args.spp, size=(width, height), device=args.device))
        print(f"alpha {alpha}: mean radiance {tiles[-1].mean():.4f}")
    pathtrace.write(args.output, np.concatenate(tiles, axis=1))
    print(f"wrote {args.output}")


if __name__ == "__main__":
    try:
        main()
    except pathtrace.UserError as e:       # one line, as pathtrace's own commands say it
        sys.exit(f"{__file__.rpartition('/')[2]}: error: {e}")
