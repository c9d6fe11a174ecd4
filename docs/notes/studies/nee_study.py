"""Time to a given error with and without next-event estimation, and side-by-side pictures of
what each shows after the same time (docs/images/nee-*.png).

For each scene: a reference (NEE, many samples, another seed), then each estimator renders
progressively, one sample per pixel per launch, and after every launch we note the elapsed
time and the relative MSE against the reference, mean((x - ref)^2 / (ref^2 + 0.01)) (the
usual relative error of rendering papers; 0.01 keeps dark pixels from dominating).

    python docs/notes/studies/nee_study.py [--device D] [--size WxH] [--seconds S] [--ref-spp N] [--json F]
                                [--light-samplers power tree ...]

With several --light-samplers, NEE runs once with each (pathtrace.rendering.choices.LIGHT_SAMPLERS): the
choice of lights by power against the light tree."""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from pathtrace.device.opencl import choose_device
from pathtrace.io.images import write_image
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene


def rel_mse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 0.01)))


def progressive(backend, scene, seconds, ref):
    r = Renderer(backend, scene)
    curve, snapshot = [], None
    start = time.perf_counter()
    while True:
        r.add_samples(1)
        r.finish()
        elapsed = time.perf_counter() - start
        image = r.mean()
        curve.append((elapsed, r.samples, rel_mse(image, ref)))
        if snapshot is None and elapsed >= 1.0:
            snapshot = image
        if elapsed >= seconds:
            return curve, snapshot if snapshot is not None else image


def time_to(curve, target):
    for elapsed, spp, err in curve:
        if err <= target:
            return elapsed, spp
    return None, None


def mitsuba_curve(scene, seconds, ref):
    """Mitsuba 3 (scalar_rgb, the variant that runs on this project's CPU machine; path
    integrator, which samples lights with MIS) on the same scene: one render per sample count,
    doubling, each timed whole."""
    import mitsuba as mi
    sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "scripts"))
    from make_references import mitsuba_scene
    mi.set_variant("scalar_rgb")
    h, w, _ = ref.shape
    curve, spp = [], 1
    while True:
        m = mitsuba_scene(mi, scene, w, h, spp)
        start = time.perf_counter()
        image = np.array(mi.render(m, seed=spp), np.float64)[..., :3]
        elapsed = time.perf_counter() - start
        curve.append((elapsed, spp, rel_mse(image, ref)))
        if elapsed >= seconds:
            return curve
        spp *= 2


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--device", default="auto")
    ap.add_argument("--size", default="320x180")
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--scenes", nargs="+", default=["simple", "demo"])
    ap.add_argument("--targets", type=float, nargs="+", default=[0.05, 0.02, 0.01])
    ap.add_argument("--json")
    ap.add_argument("--light-samplers", nargs="+", default=["auto"], metavar="SAMPLER",
                    help="how NEE chooses lights; one NEE run per sampler (default auto)")
    ap.add_argument("--images", default="docs/images")
    ap.add_argument("--mitsuba", action="store_true",
                    help="also time Mitsuba 3 (the -diffuse scenes, max depth 8, no Russian roulette)")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    backend = choose_device(args.device)
    out = {"device": backend.device.describe(), "size": args.size, "results": []}
    for name in args.scenes:
        base = load_scene(name).with_settings(width=w, height=h)
        if args.mitsuba:   # the comparison mode, in which both renderers converge to one image
            base = base.with_settings(max_depth=8, russian_roulette="off")
        ref_r = Renderer(backend, base.with_settings(nee=True, seed=999))
        while ref_r.samples < args.ref_spp:
            ref_r.add_samples(64)
        ref_r.finish()
        ref = ref_r.mean()
        shots = []
        for nee, sampler in [(False, "auto")] + [(True, s) for s in args.light_samplers]:
            curve, snap = progressive(backend, base.with_settings(nee=nee, seed=1, light_sampler=sampler),
                                      args.seconds, ref)
            shots.append(snap)
            row = {"scene": name, "nee": nee, "light_sampler": sampler, "spp_per_second": curve[-1][1] / curve[-1][0],
                   "rel_mse_after_1s": next(e for t, s, e in curve if t >= 1.0),
                   "time_to": {str(t): time_to(curve, t)[0] for t in args.targets}}
            out["results"].append(row)
            print(json.dumps(row))
        if args.mitsuba:
            curve = mitsuba_curve(base, args.seconds, ref)
            row = {"scene": name, "renderer": "Mitsuba 3 scalar_rgb, path integrator",
                   "spp_per_second": curve[-1][1] / curve[-1][0],
                   "time_to": {str(t): time_to(curve, t)[0] for t in args.targets}}
            out["results"].append(row)
            print(json.dumps(row))
        if args.images:   # left: the report's estimator; right: NEE (one per sampler); all after 1 s
            Path(args.images).mkdir(parents=True, exist_ok=True)
            write_image(Path(args.images) / f"nee-{name}.png", np.concatenate(shots, axis=1))
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
