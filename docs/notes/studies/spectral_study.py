"""How far RGB rendering stands from spectral rendering on saturated colours: the Cornell box's
red and green walls (tests/scenes/cbox.xml: reflectances 0.63, 0.065, 0.05 and 0.14, 0.45, 0.091
under a lamp of radiance 17, 12, 4), rendered by Mitsuba 3 in scalar_rgb and in scalar_spectral
(which upsamples each RGB to a smooth spectrum, Jakob and Hanika 2019, and multiplies spectra
along the path) and by pathtrace (RGB), with the same file.

Each renderer renders K independent images (seeds 0..K-1); a wall's figure is the mean over
its pixels, which pathtrace's albedo AOV finds (the pixels whose first-hit albedo is the wall's
reflectance), and its noise the standard error of that mean over the K images.

    python docs/notes/studies/spectral_study.py [--size N] [--spp S] [--renders K]
"""

import argparse
import platform
import time
from pathlib import Path

import numpy as np

import pathtrace.api as pt

SCENE = Path(__file__).resolve().parents[3] / "tests" / "scenes" / "cbox.xml"
WALLS = {"red": (0.63, 0.065, 0.05), "green": (0.14, 0.45, 0.091)}


LUMINANCE = np.array([0.2126, 0.7152, 0.0722])     # Rec. 709 / linear sRGB


def wall_means(images, masks) -> dict:
    """Per wall: (mean R, G, B and luminance over the K images, standard error of that mean),
    each (4,)."""
    out = {}
    for wall, mask in masks.items():
        per_image = np.stack([img[mask].mean(axis=0) for img in images])
        per_image = np.column_stack([per_image, per_image @ LUMINANCE])
        out[wall] = per_image.mean(axis=0), per_image.std(axis=0, ddof=1) / np.sqrt(len(images))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--renders", type=int, default=8)
    args = ap.parse_args()
    n, spp, k = args.size, args.spp, args.renders

    scene = pt.load(SCENE)
    albedo = pt.render(scene, spp=16, size=(n, n), aovs=("albedo",))["albedo"]
    masks = {wall: np.all(np.abs(albedo - rho) < 1e-3, axis=-1) for wall, rho in WALLS.items()}

    results = {}
    t = time.time()
    results["pathtrace"] = wall_means([pt.render(scene, spp=spp, size=(n, n), seed=s) for s in range(k)], masks)
    print(f"pathtrace: {time.time() - t:.0f} s")
    import mitsuba as mi
    for variant in ("scalar_rgb", "scalar_spectral"):
        mi.set_variant(variant)
        m = mi.load_file(str(SCENE), spp=spp, width=n, height=n)
        t = time.time()
        results[f"mitsuba {variant}"] = wall_means(
            [np.array(mi.render(m, seed=s), np.float64)[..., :3] for s in range(k)], masks)
        print(f"{variant}: {time.time() - t:.0f} s")

    print(f"\n{time.strftime('%Y-%m-%d')}, {platform.node()}, {n}x{n}, {k} renders of {spp} spp, "
          f"pixels: " + ", ".join(f"{w} {int(m.sum())}" for w, m in masks.items()))
    ref = results["mitsuba scalar_spectral"]
    for wall in WALLS:
        print(f"\n{wall} wall: mean R, G, B, luminance (standard error); ratio to scalar_spectral")
        for name, r in results.items():
            mean, se = r[wall]
            ratio = mean / ref[wall][0]
            ratio_se = ratio * np.sqrt((se / mean) ** 2 + (ref[wall][1] / ref[wall][0]) ** 2)
            print(f"  {name:24s} " + "  ".join(f"{m:.4f} ({s:.4f})" for m, s in zip(mean, se)) +
                  "   " + "  ".join(f"{q:.3f}±{e:.3f}" for q, e in zip(ratio, ratio_se)))


if __name__ == "__main__":
    main()
