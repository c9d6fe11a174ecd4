"""`pathtrace bench --load`: the seconds from a command to its first image, what a user waits
for before anything else. Each row writes a scene's files (or takes a scene file given) and
times `pathtrace render FILE` at 64x64 (64x36 for the height field) with 1 spp from process start
to exit, Python's start-up and imports included, best of --repeats after one untimed run that
fills the kernel cache; with --mitsuba PYTHON the same scene's Mitsuba 3 XML is loaded and
rendered with 1 spp by `mitsuba.load_file` and `mitsuba.render` in a fresh process of that
Python, timed the same way, in the same run.

The generated rows:
- `heightfield1M`: one binary PLY file of 1,000,000 triangles (the height field of
  `pathtrace bench --builds`) with a sphere, in a TOML scene;
- `meshes850`: 850 binary PLY files of tori (1,024 triangles each, with vertex normals) on a
  grid, in a pbrt-v4 scene (the layout of published scenes of many meshes)."""

import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pathtrace.errors import UserError

GENERATED = ("heightfield1M", "meshes850")
MITSUBA = """
import sys, mitsuba as mi
mi.set_variant(sys.argv[2])
mi.Bitmap(mi.render(mi.load_file(sys.argv[1]), spp=1)).write(sys.argv[3])
"""


@dataclass
class LoadTime:
    scene: str
    what: str                   # its size in words
    device: str                 # pathtrace's --device
    seconds: float              # pathtrace, command to image, the best of the repeats
    mitsuba_variant: str = ""
    mitsuba_seconds: float = None


def ply_bytes(points, faces, normals=None) -> bytes:
    """A binary little-endian PLY file of float32 vertices (with normals) and int32 triangles,
    as exporters write them."""
    names = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals is not None else [])
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(points)}"]
    header += [f"property float {n}" for n in names]
    header += [f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header"]
    columns = [points] + ([normals] if normals is not None else [])
    records = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    records["n"], records["i"] = 3, faces
    return ("\n".join(header) + "\n").encode() + np.concatenate(columns, 1).astype("<f4").tobytes() + records.tobytes()


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


def xml_scene(size, origin, target, fov, shapes, sky) -> str:
    """A Mitsuba 3 scene: a path tracer, a perspective camera, a constant sky and `shapes`."""
    return "\n".join([
        '<scene version="3.0.0">', '<integrator type="path"><integer name="max_depth" value="5"/></integrator>',
        f'<sensor type="perspective"><float name="fov" value="{fov}"/><string name="fov_axis" value="y"/>'
        f'<transform name="to_world"><lookat origin="{", ".join(map(str, origin))}" '
        f'target="{", ".join(map(str, target))}" up="0, 1, 0"/></transform>'
        '<sampler type="independent"><integer name="sample_count" value="1"/></sampler>'
        f'<film type="hdrfilm"><integer name="width" value="{size[0]}"/><integer name="height" value="{size[1]}"/>'
        '</film></sensor>', f'<emitter type="constant"><rgb name="radiance" value="{sky}"/></emitter>',
        *shapes, "</scene>", ""])


def write_height_field(folder: Path) -> tuple:
    from pathtrace.scene.builtin import height_field_mesh
    points, faces = height_field_mesh(1_000_000)
    (folder / "field.ply").write_bytes(ply_bytes(points, faces))
    (folder / "heightfield1M.toml").write_text("\n".join([
        "[camera]", "eye = [0, 1.6, 2.4]", "look_at = [0, 0, 0]", "vfov = 45", "",
        "[environment]", "color = [0.8, 0.85, 1.0]", "", "[render]", "width = 64", "height = 36", "",
        "[[meshes]]", 'name = "height field"', 'file = "field.ply"', 'material = { type = "diffuse", rho_d = 0.6 }',
        "", "[[spheres]]", 'name = "ball"', "center = [0.3, 0.35, 0.2]", "radius = 0.25",
        'material = { type = "diffuse", rho_d = [0.8, 0.3, 0.2] }', ""]))
    shapes = ['<shape type="ply"><string name="filename" value="field.ply"/>'
              '<bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>',
              '<shape type="sphere"><point name="center" x="0.3" y="0.35" z="0.2"/><float name="radius" value="0.25"/>'
              '<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.3, 0.2"/></bsdf></shape>']
    (folder / "heightfield1M.xml").write_text(xml_scene((64, 36), (0, 1.6, 2.4), (0, 0, 0), 45, shapes, "0.8, 0.85, 1.0"))
    return "heightfield1M.toml", "heightfield1M.xml", f"1 PLY file, {len(faces):,} triangles", (64, 36)


def write_meshes(folder: Path, count: int = 850) -> tuple:
    points, normals, faces = torus()
    side = int(np.ceil(np.sqrt(count)))
    for k in range(count):
        (folder / f"m{k:04d}.ply").write_bytes(ply_bytes(points + [k % side * 2.5, 0, k // side * 2.5], faces, normals))
    middle = side * 1.25
    eye, target = (middle, side * 1.2, -side * 0.6), (middle, 0, middle)
    pbrt = ['Integrator "path" "integer maxdepth" [ 4 ]', 'Sampler "independent" "integer pixelsamples" 1',
            'Film "rgb" "integer xresolution" 64 "integer yresolution" 64', "Scale -1 1 1",
            f"LookAt {' '.join(map(str, eye))}  {' '.join(map(str, target))}  0 1 0",
            'Camera "perspective" "float fov" 60', "WorldBegin", 'LightSource "infinite" "rgb L" [ 1 1 1 ]',
            'Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]']
    pbrt += [f'Shape "plymesh" "string filename" "m{k:04d}.ply"' for k in range(count)]
    (folder / f"meshes{count}.pbrt").write_text("\n".join(pbrt) + "\n")
    shapes = [f'<shape type="ply"><string name="filename" value="m{k:04d}.ply"/>'
              '<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>' for k in range(count)]
    (folder / f"meshes{count}.xml").write_text(xml_scene((64, 64), eye, target, 60, shapes, "1"))
    return f"meshes{count}.pbrt", f"meshes{count}.xml", f"{count} PLY files, {count * len(faces):,} triangles", (64, 64)


def best_time(command, repeats: int, cwd) -> float:
    """The shortest of `repeats` runs of `command`, from process start to exit; a failure is one
    line naming the command and its last line of output."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        r = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
        times.append(time.perf_counter() - start)
        if r.returncode:
            last = (r.stderr.strip().splitlines() or ["(no output)"])[-1]
            raise UserError(f"bench --load: {' '.join(map(str, command[:6]))} ... failed: {last}")
    return min(times)


def run_load(device: str, scene_files, repeats: int, mitsuba_python: str = None,
             variant: str = "llvm_ad_rgb", log=print) -> list[LoadTime]:
    """The generated rows, then one per file of scene_files (Mitsuba's column for XML files)."""
    folder = Path(tempfile.mkdtemp(prefix="pathtrace-load-"))
    results = []
    try:
        rows = [write_height_field(folder), write_meshes(folder)]
        rows += [(str(Path(f).resolve()), str(Path(f).resolve()) if f.lower().endswith(".xml") else None,
                  "/".join(Path(f).resolve().parts[-3:])[-36:], (64, 64)) for f in scene_files]
        for scene, xml, what, size in rows:
            render = [sys.executable, "-m", "pathtrace", "render", scene, "--size", f"{size[0]}x{size[1]}",
                      "--spp", "1", "--device", device, "-o", str(folder / "out.exr"), "-q"]
            best_time(render, 1, folder)                   # fills the kernel cache
            r = LoadTime(Path(scene).stem, what, device, best_time(render, repeats, folder))
            if mitsuba_python and xml:
                mitsuba = [mitsuba_python, "-c", MITSUBA, xml, variant, str(folder / "mitsuba.exr")]
                r.mitsuba_variant, r.mitsuba_seconds = variant, best_time(mitsuba, repeats, folder)
            log(format_load_row(r))
            results.append(r)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return results


LOAD_HEADER = f"{'scene':<16} {'what':<36} {'device':<8} {'pathtrace s':>11} {'Mitsuba 3 s':>22} {'ratio':>6}"


def format_load_row(r: LoadTime) -> str:
    theirs = f"{r.mitsuba_seconds:.2f} ({r.mitsuba_variant})" if r.mitsuba_seconds is not None else "-"
    ratio = f"{r.mitsuba_seconds / r.seconds:.2f}" if r.mitsuba_seconds is not None else "-"
    return f"{r.scene:<16} {r.what:<36} {r.device:<8} {r.seconds:>11.2f} {theirs:>22} {ratio:>6}"
