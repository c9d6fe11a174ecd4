"""Equal-time path tracing against BDPT, against reference renders (docs/notes/performance-2026-11.md,
2026-11-29 and 2026-11-30): python docs/notes/studies/bdpt_equal_time.py SECONDS OUT_FOLDER SCENE...
where a SCENE is a name, whose folder is unpacked from ../shared/scenes into $BITTERLI
(SCENE/pbrt/scene-v4.pbrt and Tungsten's TungstenRender.exr, rendered at half its resolution), or
FILE=REFERENCE, a scene file and a reference EXR rendered at the reference's own resolution
(volumetric-caustic's pbrt-v4 BDPT render in ../shared/references/pbrt-v4/bitterli); prints
samples, time per sample, means and the mean relative error of 8x8-pixel blocks, and writes
reference | path | bdpt (| bdpt with caustic photons, where the file asks for pbrt's sppm or
$PHOTON_RADIUS gives their radius), and each image (NAME-INTEGRATOR.npy). With `reference
SECONDS FILE OUT.exr WIDTH HEIGHT` it renders a reference instead (below)."""
import os
import sys
import time

import numpy as np
import OpenEXR
from PIL import Image

from pathtrace.device.opencl import choose_device
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene

be = choose_device("gpu")
if sys.argv[1] == "reference":
    # python .../bdpt_equal_time.py reference SECONDS FILE OUT.exr WIDTH HEIGHT: FILE rendered by
    # its own integrator for SECONDS, a reference where no other renderer's converges
    seconds, scene_file, out, w, h = float(sys.argv[2]), sys.argv[3], sys.argv[4], int(sys.argv[5]), int(sys.argv[6])
    r = Renderer(be, load_scene(scene_file).with_settings(seed=12345), w, h)
    t = time.perf_counter()
    while time.perf_counter() - t < seconds:
        r.add_samples(64); r.finish()
    m = r.mean()[..., :3].astype(np.float32)
    print(f"{scene_file}: {r.samples} spp at {w}x{h} in {time.perf_counter() - t:.1f} s, mean {m.mean():.5f}")
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, {"RGB": m}) as f:
        f.write(out)
    sys.exit()
budget = float(sys.argv[1])
out = sys.argv[2]
for arg in sys.argv[3:]:
    if "=" in arg:
        scene_file, reference = arg.split("=")
        name, shrink = os.path.basename(scene_file).split(".")[0], 1
    else:
        folder = f"{os.environ.get('BITTERLI', '.')}/{arg}/pbrt"
        scene_file, reference, name, shrink = f"{folder}/scene-v4.pbrt", f"{folder}/TungstenRender.exr", arg, 2
    sc = load_scene(scene_file)
    with OpenEXR.File(reference) as f:
        ch = f.channels()
        ref = ch["RGB"].pixels if "RGB" in ch else np.stack([ch[c].pixels for c in "RGB"], -1)
    # Tungsten's water-caustic holds NaN and negative pixels: taken as black
    ref = np.clip(np.nan_to_num(np.asarray(ref, np.float64)[..., :3], nan=0.0, posinf=0.0), 0, None)
    H, W = ref.shape[0] // shrink, ref.shape[1] // shrink
    ref = ref.reshape(H, shrink, W, shrink, 3).mean((1, 3))
    imgs = [ref]
    print(name, W, H, sc.settings.max_depth, flush=True)
    # BDPT with caustic photons too where the file asks for them (pbrt's sppm) or $PHOTON_RADIUS gives a radius
    radius = float(os.environ.get("PHOTON_RADIUS", sc.settings.photon_radius))
    for integ in ("path", "bdpt") + (("bdpt+photons",) if radius > 0 else ()):
        t0 = time.perf_counter()
        r = Renderer(be, sc.with_settings(integrator=integ.split("+")[0], seed=1,
                                          photon_radius=radius if integ == "bdpt+photons" else 0.0), W, H)
        r.add_samples(1); r.finish(); r.reset()
        built = time.perf_counter() - t0
        t = time.perf_counter(); spp = 1
        while time.perf_counter() - t < budget:
            r.add_samples(spp); r.finish(); spp = min(spp * 2, 64)
        sec = time.perf_counter() - t
        m = r.mean()
        b = lambda im: im.reshape(H // 8, 8, W // 8, 8, 3).mean((1, 3)).mean(-1)
        rel = np.abs(b(m) - b(ref)) / np.maximum(b(ref), 1e-3)
        print(f"  {integ}: {r.samples} spp in {sec:.1f} s ({sec / r.samples * 1e3:.2f} ms/spp, "
              f"{sec / r.samples / (W * H) * 1e9:.1f} ns/sample; first pass after {built:.1f} s); "
              f"mean {m.mean():.4f} ref {ref.mean():.4f}; 8x8-block rel err {rel.mean():.4f}", flush=True)
        imgs.append(m)
        np.save(f"{out}/{name}-{integ.replace('+', '-')}.npy", m)
    im = np.concatenate(imgs, 1)
    im = np.clip(np.where(im <= 0.0031308, 12.92 * im, 1.055 * np.power(np.maximum(im, 0), 1 / 2.4) - 0.055), 0, 1)
    Image.fromarray((im * 255).astype(np.uint8)).save(f"{out}/{name}-ref-path-bdpt.png")
