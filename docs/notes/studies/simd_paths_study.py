"""Whole paths in SIMD lanes on CPUs, an experiment for #31's CPU goal (docs/notes/performance-2026-11.md,
2026-11-27): pathtrace's estimator (depth 8, next-event estimation, the power heuristic) written
with LANES paths per work-item in OpenCL vectors (docs/notes/studies/simd_paths_study.cl), for scenes of
spheres with diffuse or emitting materials under a constant sky, such as simple-diffuse, timed
against the renderer's megakernel on the same device in the same run. Not part of the renderer.

    python docs/notes/studies/simd_paths_study.py [SCENE] [--device cpu] [--size 480x270] [--spp 32]
                                       [--lanes 8 16]

Prints, best of three each, the megakernel's seconds (pathtrace.bench.report.measure, the timed region
of `pathtrace bench`) and each lane width's, and the images' means, which agree within noise (the
two draw different random numbers and choose lights with different probabilities)."""

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pyopencl as cl

from pathtrace.bench.report import estimator_settings, measure
from pathtrace.cli.options import _int_range, _size
from pathtrace.device.opencl import choose_device
from pathtrace.errors import UserError
from pathtrace.scene import load_scene
from simd_study import lanes_header

HERE = Path(__file__).resolve().parent


def lanes_program(backend, lanes: int):
    return cl.Program(backend.context, lanes_header(lanes) + (HERE / "simd_paths_study.cl").read_text()).build()


def scene_tables(scene):
    """The kernel's sphere, albedo, emission and light tables, refusing what it cannot render."""
    if len(scene.meshes) or scene.environment.image.size != 3:
        raise SystemExit(f"{scene.name}: the study renders spheres under a constant sky only")
    albedo, emission = [], []
    for m in scene.sphere_material:
        material = scene.materials.get(int(m))
        if material.type not in ("diffuse", "black"):
            raise SystemExit(f"{scene.name}: material {material.type} is not diffuse or an emitter")
        albedo.append(material.params.get("rho_d", np.zeros(3)) * np.ones(3))
        emission.append(material.emission)
    pad = lambda rows: np.column_stack([np.asarray(rows, np.float32), np.zeros(len(rows), np.float32)])
    albedo, emission = pad(albedo), pad(emission)
    lights = np.flatnonzero(emission[:, :3].max(axis=1) > 0).astype(np.int32)
    sky = scene.environment.image.reshape(3) * scene.environment.intensity
    return np.ascontiguousarray(scene.spheres, np.float32), albedo, emission, lights, sky


def camera_plane(camera, width: int, height: int):
    """The eye, the image's top-left corner and the steps of one pixel right and down."""
    eye, look_at, up = (np.asarray(v, np.float64) for v in (camera.eye, camera.look_at, camera.up))
    forward = (look_at - eye) / np.linalg.norm(look_at - eye)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    down = -np.cross(right, forward)
    half_h = np.tan(np.radians(camera.vfov) / 2)
    half_w = half_h * width / height
    corner = eye + forward - right * half_w - down * half_h
    return [np.append(v, 0).astype(np.float32) for v in (eye, corner, right * 2 * half_w / width,
                                                          down * 2 * half_h / height)]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", default="simple-diffuse")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--size", type=_size, default=(480, 270), metavar="WxH")
    ap.add_argument("--spp", type=_int_range(1, 4096), default=32)
    ap.add_argument("--lanes", type=int, nargs="+", choices=(2, 4, 8, 16), default=[8, 16])
    args = ap.parse_args()
    width, height = args.size
    try:
        backend = choose_device(args.device)
        scene = load_scene(args.scene)
    except UserError as e:
        sys.exit(f"simd_paths_study: {e}")
    spheres, albedo, emission, lights, sky = scene_tables(scene)
    eye, corner, step_x, step_y = camera_plane(scene.camera, width, height)
    pixels = width * height
    mf = cl.mem_flags
    table = lambda a: cl.Buffer(backend.context, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=a)
    tables = [table(spheres), np.int32(len(spheres)), table(albedo), table(emission),
              table(lights if len(lights) else np.zeros(1, np.int32)), np.int32(len(lights))]
    env_pick = np.float32(0.5 if len(lights) else 1.0)
    out = cl.Buffer(backend.context, mf.WRITE_ONLY, 12 * pixels)
    print(f"{backend.device.describe()}: {scene.name}, {width}x{height}, {args.spp} spp, depth 8 with NEE")

    rounds = [measure([backend], scene, "depth8+nee", width, height, args.spp, (None, None)) for _ in range(3)]
    best = min(rounds, key=lambda r: r.render_seconds)
    print(f"megakernel            {best.render_seconds:.3f} s  mean {best.mean:.4f}", flush=True)
    for lanes in args.lanes:
        if pixels % lanes:
            raise SystemExit(f"{pixels} pixels are not a multiple of {lanes} lanes")
        kernel = cl.Kernel(lanes_program(backend, lanes), "render_lanes")
        launch = lambda spp: kernel(backend.queue, (pixels // lanes,), None, *tables, np.append(sky, 0).astype(np.float32),
                                    env_pick, eye, corner, step_x, step_y, np.int32(width), np.int32(spp),
                                    np.int32(estimator_settings("depth8+nee")["max_depth"]), out, np.int32(pixels))
        launch(1)
        backend.queue.finish()
        seconds = np.inf
        for _ in range(3):
            start = time.perf_counter()
            launch(args.spp)
            backend.queue.finish()
            seconds = min(seconds, time.perf_counter() - start)
        image = np.empty((3, pixels), np.float32)
        cl.enqueue_copy(backend.queue, image, out)
        print(f"{lanes:2d} lanes              {seconds:.3f} s  mean {image.mean():.4f}  "
              f"({best.render_seconds / seconds:.2f}x the megakernel)", flush=True)


if __name__ == "__main__":
    main()
