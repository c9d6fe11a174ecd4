"""Regenerates tests/references/bsdfs/principled.npz: Mitsuba 3's `principled` BSDF evaluated at
pairs of directions, the independent reference of tests/test_principled.py.

For each parameter set of CASES, pairs (wo, wi) in the local shading frame: wo at a few
elevations and azimuths, from outside and (where spec_trans is not 0) inside, and for each, wi
spread over the sphere and gathered about the mirror and refracted directions where the
specular lobes peak. Mitsuba's eval is f |cos theta_i| with its wi the direction towards the
viewer; the file holds f (that cos divided out) and Mitsuba's pdf.

    python scripts/make_principled_evals.py      (needs `pip install mitsuba`)
"""

import json
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent.parent / "tests" / "references" / "bsdfs" / "principled.npz"
CASES = [
    {},
    {"base_color": [0.8, 0.3, 0.1], "roughness": 0.3, "metallic": 0.4, "spec_tint": 0.6, "sheen": 0.8,
     "sheen_tint": 0.5, "clearcoat": 0.9, "clearcoat_gloss": 0.7},
    {"base_color": [0.95, 0.7, 0.3], "roughness": 0.5, "anisotropic": 0.8, "metallic": 1.0},
    {"base_color": [0.9, 0.8, 0.6], "roughness": 0.2, "spec_trans": 0.8, "eta": 1.45},
    {"base_color": [0.3, 0.6, 0.2], "roughness": 0.6, "spec_trans": 0.5, "metallic": 0.2, "specular": 0.7,
     "clearcoat": 0.5, "flatness": 0.6, "spec_tint": 0.3, "anisotropic": 0.4},
    {"base_color": [0.2, 0.6, 0.9], "roughness": 0.9, "flatness": 1.0, "sheen": 1.0, "sheen_tint": 1.0},
]


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def direction_pairs(rng, inside):
    """(wo, wi) pairs: wo at elevations 15-80 degrees and several azimuths (below the surface
    too where `inside`), wi uniform on the sphere and about wo's mirror and refraction."""
    pairs = []
    for theta in (15, 50, 80) + ((110, 160) if inside else ()):
        for phi in (0, 40, 130):
            t, p = np.radians(theta), np.radians(phi)
            wo = np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
            uniform = unit(rng.normal(size=(24, 3)))
            mirror = unit(np.array([-wo[0], -wo[1], wo[2]]) + 0.3 * rng.normal(size=(12, 3)))
            through = unit(-wo + 0.3 * rng.normal(size=(12, 3)))
            for wi in np.concatenate([uniform, mirror, through]):
                pairs.append((wo, wi))
    return np.array(pairs)


def main():
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    OUT.parent.mkdir(exist_ok=True)
    rng = np.random.default_rng(1)
    ctx = mi.BSDFContext()
    case_ids, wos, wis, fs, pdfs = [], [], [], [], []
    for k, params in enumerate(CASES):
        d = {"type": "principled"}
        for name, value in params.items():
            d[name] = {"type": "rgb", "value": value} if isinstance(value, list) else value
        bsdf = mi.load_dict(d)
        for wo, wi in direction_pairs(rng, params.get("spec_trans", 0) > 0):
            si = mi.SurfaceInteraction3f()
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            si.wi = mi.Vector3f(*wo)
            value = np.array(bsdf.eval(ctx, si, mi.Vector3f(*wi)), np.float64).reshape(3)
            case_ids.append(k)
            wos.append(wo)
            wis.append(wi)
            fs.append(value / abs(wi[2]))
            pdfs.append(float(bsdf.pdf(ctx, si, mi.Vector3f(*wi))))
    np.savez_compressed(OUT, cases=json.dumps(CASES), case=np.array(case_ids), wo=np.array(wos), wi=np.array(wis),
                        f=np.array(fs), pdf=np.array(pdfs), version=mi.__version__)
    print(f"{OUT}: {len(case_ids)} pairs, Mitsuba {mi.__version__}")


if __name__ == "__main__":
    main()
