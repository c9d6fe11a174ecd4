"""Time from command to first image of a scene of many PLY meshes, as a pbrt-v4 file in pathtrace
and as the same scene's Mitsuba 3 XML in Mitsuba 3, on one machine in one run (docs/pbrt.md).

The scene: N binary PLY meshes (tori of 1,024 triangles with normals) on a grid under a constant
sky, a 64x64 film, 1 spp. pathtrace runs `pathtrace render scene.pbrt` (its kernel cache warm,
from a first run); Mitsuba runs `mitsuba.load_file` and `mitsuba.render` in a fresh Python. Each
is timed from process start to exit, best of --repeats.

    python scripts/load_race.py [--meshes 850] [--repeats 3] [--mitsuba-python /tmp/mi/bin/python]
                                [--variant scalar_rgb]"""

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

MITSUBA = """
import sys, mitsuba as mi
mi.set_variant(sys.argv[2])
scene = mi.load_file(sys.argv[1])
image = mi.render(scene, spp=1)
mi.Bitmap(image).write(sys.argv[3])
"""


def torus(nu=32, nv=16, r0=1.0, r1=0.35):
    """A torus of 2 nu nv triangles, counter-clockwise seen from outside, with its normals."""
    u = np.arange(nu) / nu * 2 * np.pi
    v = np.arange(nv) / nv * 2 * np.pi
    U, V = np.meshgrid(u, v, indexing="ij")
    centre = np.stack([np.cos(U), np.zeros_like(U), np.sin(U)], -1)
    normal = np.stack([np.cos(U) * np.cos(V), np.sin(V), np.sin(U) * np.cos(V)], -1)
    points = (r0 * centre + r1 * normal).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = i * nv + j, ((i + 1) % nu) * nv + j
    c, d = i * nv + (j + 1) % nv, ((i + 1) % nu) * nv + (j + 1) % nv
    faces = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])
    return points, normal.reshape(-1, 3), faces


def write_ply(path, points, normals, faces):
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\nproperty float x\n"
              "property float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    records = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    records["n"], records["i"] = 3, faces
    path.write_bytes(header.encode() + np.concatenate([points, normals], 1).astype("<f4").tobytes()
                     + records.tobytes())


def make_scene(folder: Path, count: int):
    points, normals, faces = torus()
    side = int(np.ceil(np.sqrt(count)))
    for k in range(count):
        write_ply(folder / f"m{k:04d}.ply", points + [k % side * 2.5, 0, k // side * 2.5], normals, faces)
    middle = side * 1.25
    pbrt = ['Integrator "path" "integer maxdepth" [ 4 ]', 'Sampler "independent" "integer pixelsamples" 1',
            'Film "rgb" "integer xresolution" 64 "integer yresolution" 64', "Scale -1 1 1",
            f"LookAt {middle} {side * 1.2} {-side * 0.6}  {middle} 0 {middle}  0 1 0",
            'Camera "perspective" "float fov" 60', "WorldBegin", 'LightSource "infinite" "rgb L" [ 1 1 1 ]',
            'Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]']
    pbrt += [f'Shape "plymesh" "string filename" "m{k:04d}.ply"' for k in range(count)]
    (folder / "scene.pbrt").write_text("\n".join(pbrt) + "\n")
    xml = ['<scene version="3.0.0">', '<integrator type="path"><integer name="max_depth" value="5"/></integrator>',
           '<sensor type="perspective"><float name="fov" value="60"/><transform name="to_world">'
           f'<lookat origin="{middle}, {side * 1.2}, {-side * 0.6}" target="{middle}, 0, {middle}" up="0, 1, 0"/>'
           '</transform><sampler type="independent"><integer name="sample_count" value="1"/></sampler>'
           '<film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/></film></sensor>',
           '<emitter type="constant"/>', '<bsdf type="diffuse" id="d"/>']
    xml += [f'<shape type="ply"><string name="filename" value="m{k:04d}.ply"/><ref id="d"/></shape>'
            for k in range(count)]
    (folder / "scene.xml").write_text("\n".join(xml + ["</scene>"]) + "\n")


def best_time(command, repeats, cwd):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        r = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
        times.append(time.perf_counter() - start)
        if r.returncode:
            sys.exit(f"{' '.join(map(str, command))} failed: {r.stderr.strip().splitlines()[-1:]}")
    return min(times)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--meshes", type=int, default=850)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--mitsuba-python", default="/tmp/mi/bin/python")
    p.add_argument("--variant", default="scalar_rgb")
    args = p.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="load_race_"))
    try:
        make_scene(folder, args.meshes)
        pathtrace = [sys.executable, "-m", "pathtrace", "render", "scene.pbrt", "-o", "p.exr", "-q"]
        subprocess.run(pathtrace, cwd=folder, capture_output=True)          # the kernel cache
        mitsuba = [args.mitsuba_python, "-c", MITSUBA, "scene.xml", args.variant, "m.exr"]
        t_p = best_time(pathtrace, args.repeats, folder)
        t_m = best_time(mitsuba, args.repeats, folder)
        print(f"{args.meshes} PLY meshes ({args.meshes * 1024} triangles), command to a 64x64 image, best of "
              f"{args.repeats}: pathtrace (pbrt-v4 file) {t_p:.2f} s, Mitsuba 3 {args.variant} (XML) {t_m:.2f} s, "
              f"ratio {t_m / t_p:.2f}")
    finally:
        shutil.rmtree(folder)


if __name__ == "__main__":
    main()
