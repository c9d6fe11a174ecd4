"""The benchmark scenes that are files: written on demand into a folder, each as pathtrace reads
it and as Mitsuba 3 XML, so that both renderers time the same work (`pathtrace bench --load`,
and `pathtrace bench --scenes tori400-textured`).

- `heightfield1M`: one binary PLY file of 1,000,000 triangles (the height field of
  `pathtrace bench --builds`) with a sphere, in a TOML scene;
- `meshes850`: 850 binary PLY files of tori (1,024 triangles each, with vertex normals) on a
  grid, in a pbrt-v4 scene (the layout of published scenes of many meshes);
- `meshes850-obj`: the same tori as OBJ files written as Blender writes them, in Mitsuba XML
  (the layout of scenes exported from Blender): a row of `bench --first-image` and of the
  report's table (`--scenes meshes850-obj`), not of `bench --load`;
- `tori400-textured`: 400 tori with uvs, each with its own 256x256 bitmap texture (a PNG file),
  on a textured ground, under a sky and a sphere lamp, in Mitsuba XML (which pathtrace reads too):
  the "several hundred textured meshes" row of the mesh benchmarks;
- `tori400-materials`: the same tori and images under seven materials in turn (MATERIALS: diffuse,
  rough and smooth plastic over the image, rough and smooth metals, rough and smooth glass), as a
  real interior mixes them: #59's "several hundred textured meshes with at least six materials"."""

from pathlib import Path

import numpy as np

from pathtrace.scene.mitsuba_writer import ply_bytes, scene_xml


def torus(nu=32, nv=16, r0=1.0, r1=0.35):
    """A torus of 2 nu nv triangles, counter-clockwise seen from outside: its points, normals,
    uvs (u around the ring, v around the tube; the seams' vertices doubled so that uvs do not
    wrap inside a triangle) and triangles."""
    U, V = np.meshgrid(np.linspace(0, 2 * np.pi, nu + 1), np.linspace(0, 2 * np.pi, nv + 1), indexing="ij")
    centre = np.stack([np.cos(U), np.zeros_like(U), np.sin(U)], -1)
    normal = np.stack([np.cos(U) * np.cos(V), np.sin(V), np.sin(U) * np.cos(V)], -1)
    points = (r0 * centre + r1 * normal).reshape(-1, 3)
    uvs = np.stack([U / (2 * np.pi), V / (2 * np.pi)], -1).reshape(-1, 2)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = i * (nv + 1) + j, (i + 1) * (nv + 1) + j
    faces = np.concatenate([np.stack([a, a + 1, b], -1).reshape(-1, 3), np.stack([b, a + 1, b + 1], -1).reshape(-1, 3)])
    return points, normal.reshape(-1, 3), uvs, faces


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
    xml = scene_xml((64, 36), (0, 1.6, 2.4), (0, 0, 0), (0, 1, 0), 45, 1, 5, (0.8, 0.85, 1.0), shapes)
    (folder / "heightfield1M.xml").write_text(xml)
    return "heightfield1M.toml", "heightfield1M.xml", f"1 PLY file, {len(faces):,} triangles", (64, 36)


def write_meshes(folder: Path, count: int = 850, size: tuple = (64, 64)) -> tuple:
    """Writes `meshes850` (the module's docstring) into `folder`, with `count` tori and a film of
    `size` pixels; returns the pbrt-v4 file's name, the XML file's, the scene in words and the
    size."""
    points, normals, _, faces = torus()
    side = int(np.ceil(np.sqrt(count)))
    for k in range(count):
        (folder / f"m{k:04d}.ply").write_bytes(ply_bytes(points + [k % side * 2.5, 0, k // side * 2.5], faces, normals))
    middle = side * 1.25
    eye, target = (middle, side * 1.2, -side * 0.6), (middle, 0, middle)
    pbrt = ['Integrator "path" "integer maxdepth" [ 4 ]', 'Sampler "independent" "integer pixelsamples" 1',
            f'Film "rgb" "integer xresolution" {size[0]} "integer yresolution" {size[1]}', "Scale -1 1 1",
            f"LookAt {' '.join(map(str, eye))}  {' '.join(map(str, target))}  0 1 0",
            'Camera "perspective" "float fov" 60', "WorldBegin", 'LightSource "infinite" "rgb L" [ 1 1 1 ]',
            'Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]']
    pbrt += [f'Shape "plymesh" "string filename" "m{k:04d}.ply"' for k in range(count)]
    (folder / f"meshes{count}.pbrt").write_text("\n".join(pbrt) + "\n")
    shapes = [f'<shape type="ply"><string name="filename" value="m{k:04d}.ply"/>'
              '<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>' for k in range(count)]
    (folder / f"meshes{count}.xml").write_text(scene_xml(size, eye, target, (0, 1, 0), 60, 1, 5, 1.0, shapes))
    return f"meshes{count}.pbrt", f"meshes{count}.xml", f"{count} PLY files, {count * len(faces):,} triangles", size


def torus_obj(nu=32, nv=16) -> str:
    """torus()'s torus as Blender writes an OBJ file: each point once (v, with its normal vn),
    the uv seams' corners doubled only in vt, faces of v/vt/vn indices, and its uvs with v = 0 at
    the bottom, as OBJ places them (pathtrace.scene.meshes flips them to Mitsuba's)."""
    points, normals, uvs, _ = torus(nu, nv)
    grid = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
    shared = grid[:nu, :nv].reshape(-1)                  # the points before the seams' copies
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    point = lambda i, j: (i % nu) * nv + j % nv + 1      # noqa: E731
    corners = [(i, j), (i, j + 1), (i + 1, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
    rows = np.stack([np.stack([point(a, b), grid[a, b] + 1, point(a, b)], -1) for a, b in corners], 2)
    faces = rows.reshape(-1, 2, 3, 3).transpose(1, 0, 2, 3).reshape(-1, 3, 3)
    return "".join(["# Blender 4.2.0\no torus\n", *(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in points[shared]),
                    *(f"vn {x:.4f} {y:.4f} {z:.4f}\n" for x, y, z in normals[shared]),
                    *(f"vt {u:.6f} {1 - v:.6f}\n" for u, v in uvs), "s 1\nusemtl Material\n",
                    *("f " + " ".join("/".join(map(str, c)) for c in face) + "\n" for face in faces)])


def write_obj_meshes(folder: Path, count: int = 850, size: tuple = (64, 64)) -> Path:
    """`meshes850-obj` (the module's docstring) in `folder`, with a film of `size` pixels: its
    XML file."""
    text = torus_obj()
    side = int(np.ceil(np.sqrt(count)))
    shapes = []
    for k in range(count):
        (folder / f"o{k:04d}.obj").write_text(text)
        shapes.append(f'<shape type="obj"><string name="filename" value="o{k:04d}.obj"/>'
                      f'<transform name="to_world"><translate x="{k % side * 2.5}" z="{k // side * 2.5}"/></transform>'
                      '<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>')
    middle = side * 1.25
    path = folder / f"meshes{count}-obj.xml"
    path.write_text(scene_xml(size, (middle, side * 1.2, -side * 0.6), (middle, 0, middle), (0, 1, 0), 60, 1, 5,
                              1.0, shapes))
    return path


# The materials of `tori400-materials`, the k-th torus's the (k mod 7)-th, its image where the
# material has one ({image}: the bitmap's file name)
IMAGE = '<texture type="bitmap" name="{name}"><string name="filename" value="{{image}}"/></texture>'
MATERIALS = (
    '<bsdf type="diffuse">' + IMAGE.format(name="reflectance") + '</bsdf>',
    '<bsdf type="roughplastic"><float name="alpha" value="0.15"/>' + IMAGE.format(name="diffuse_reflectance") + '</bsdf>',
    '<bsdf type="plastic">' + IMAGE.format(name="diffuse_reflectance") + '</bsdf>',
    '<bsdf type="roughconductor"><string name="material" value="Cu"/><float name="alpha" value="0.2"/></bsdf>',
    '<bsdf type="conductor"><string name="material" value="Al"/></bsdf>',
    '<bsdf type="roughdielectric"><float name="alpha" value="0.1"/><float name="int_ior" value="1.5"/></bsdf>',
    '<bsdf type="dielectric"><float name="int_ior" value="1.5"/></bsdf>',
)


def write_textured_tori(folder: Path, count: int = 400, size: tuple = (1920, 1080), materials: tuple = None) -> Path:
    """`tori400-textured` (the module's docstring) in `folder`, with a film of `size` pixels: its
    XML file. With `materials` (such as MATERIALS), `tori400-materials`: the k-th torus's BSDF is
    the (k mod len(materials))-th, its image as the BSDF's `{image}` names it."""
    from PIL import Image
    points, normals, uvs, faces = torus()
    side = int(np.ceil(np.sqrt(count)))
    rng = np.random.default_rng(400)
    y, x = np.mgrid[0:256, 0:256] / 256
    shapes = []
    for k in range(count):
        # each its own image: stripes and rings in two colours of its own
        a, b = rng.uniform(0.1, 0.9, (2, 3))
        f = rng.uniform(2, 12, 2)
        bsdf = materials[k % len(materials)] if materials else MATERIALS[0]
        if "{image}" in bsdf:      # (a metal's or a glass's torus has none)
            mix = (0.5 + 0.5 * np.sin(2 * np.pi * (f[0] * x + 0.5 * np.sin(2 * np.pi * f[1] * y[:, :1]))))[..., None]
            # the fastest zlib level: the default spent 5 s of the scene's writing on compression
            Image.fromarray(np.uint8(255 * (a * mix + b * (1 - mix)))).save(folder / f"t{k:04d}.png", compress_level=1)
        (folder / f"torus{k:04d}.ply").write_bytes(ply_bytes(points + [k % side * 2.5, 0.35, k // side * 2.5],
                                                             faces, normals, uvs))
        bsdf = bsdf.format(image=f"t{k:04d}.png")
        shapes.append(f'<shape type="ply"><string name="filename" value="torus{k:04d}.ply"/>{bsdf}</shape>')
    check = np.where((np.floor(x * 8) + np.floor(y * 8)) % 2 == 0, 200, 60).astype(np.uint8)
    Image.fromarray(check).save(folder / "ground.png")
    extent = side * 2.5 + 2
    shapes.append(f'<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/>'
                  f'<scale value="{extent / 2}"/><translate x="{side * 1.25 - 1.25}" z="{side * 1.25 - 1.25}"/>'
                  '</transform><bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
                  '<string name="filename" value="ground.png"/><transform name="to_uv"><scale value="8"/></transform>'
                  '</texture></bsdf></shape>')
    shapes.append(f'<shape type="sphere"><point name="center" x="{side * 0.3}" y="{side * 1.2}" z="{-side * 0.6}"/>'
                  f'<float name="radius" value="{side * 0.1}"/><emitter type="area"><rgb name="radiance" value="30"/>'
                  '</emitter></shape>')
    middle = side * 1.25
    path = folder / f"tori{count}-{'materials' if materials else 'textured'}.xml"
    path.write_text(scene_xml(size, (middle, side * 0.6, -side * 0.3), (middle, 0, middle * 0.8), (0, 1, 0),
                              50, 1, 5, (0.5, 0.6, 0.8), shapes))
    return path
