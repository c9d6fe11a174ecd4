"""veach-bidir's pbrt-v4 file as Mitsuba 3 XML, so that a renderer other than pathtrace renders
what the file says (docs/notes/performance-2026-11.md, 2026-11-30, tenth session): its right
half stands 3-8 % above Tungsten's reference in pathtrace's path tracer and BDPT alike. Written
from the file by hand, not by pathtrace's reader: the camera from the file's Transform (pbrt's
world-to-camera, its 16 numbers column by column), the shapes' PLY files as they are, the two
emitting quads as PLY files, pbrt's diffuse and conductor two-sided as pbrt's BSDFs are,
maxdepth 7 (bounces) as Mitsuba's max_depth 8 (segments), and the file's triangle filter of
radius 1 as Mitsuba's tent (radius 1), at 64x64. The sampler's count is a placeholder: the
samples per pixel are given to mi.render(scene, spp=...).
python docs/notes/studies/veach_bidir_mitsuba.py FOLDER OUT.xml, where FOLDER holds
scene-v4.pbrt and its models/."""
import sys
from pathlib import Path

import numpy as np

from pathtrace.scene.mitsuba_writer import ply_bytes

folder, out = Path(sys.argv[1]), Path(sys.argv[2])
text = (folder / "scene-v4.pbrt").read_text()
transform = np.array(text.split("Transform [")[1].split("]")[0].split(), float).reshape(4, 4).T
to_world = np.linalg.inv(transform)
origin, forward, up = to_world[:3, 3], to_world[:3, 2], to_world[:3, 1]

BSDFS = {
    "Diffuse": '<bsdf type="twosided" id="Diffuse"><bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></bsdf>',
    "Wood": '<bsdf type="twosided" id="Wood"><bsdf type="diffuse"><rgb name="reflectance" value="0.32963, 0.257976, 0.150292"/></bsdf></bsdf>',
    "Glass": '<bsdf type="dielectric" id="Glass"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>',
    "Lamp": ('<bsdf type="twosided" id="Lamp"><bsdf type="roughconductor"><string name="distribution" value="ggx"/>'
             '<float name="alpha" value="0.25"/><rgb name="eta" value="2.865601, 2.119182, 1.940077"/>'
             '<rgb name="k" value="3.032326, 2.056108, 1.616293"/></bsdf></bsdf>'),
}

shapes, material = [], None
for block in text.split("WorldBegin")[1].split("\n"):
    line = block.strip()
    if line.startswith("NamedMaterial"):
        material = line.split('"')[1]
    elif line.startswith('"string filename"') and "models/" in line:
        name = line.split('"')[3]
        shapes.append(f'<shape type="ply"><string name="filename" value="{folder / name}"/><ref id="{material}"/></shape>')
for k, light in enumerate(text.split("AreaLightSource")[1:]):
    radiance = light.split('"rgb L" [')[1].split("]")[0].split()
    points = np.array(light.split('"point3 P" [')[1].split("]")[0].split(), float).reshape(-1, 3)
    normals = np.array(light.split('"normal N" [')[1].split("]")[0].split(), float).reshape(-1, 3)
    faces = np.array(light.split('"integer indices" [')[1].split("]")[0].split(), int).reshape(-1, 3)
    ply = out.parent / f"{out.stem}-light{k}.ply"
    ply.write_bytes(ply_bytes(points, faces, normals))
    shapes.append(f'<shape type="ply"><string name="filename" value="{ply.resolve()}"/>'
                  '<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>'
                  f'<emitter type="area"><rgb name="radiance" value="{", ".join(radiance)}"/></emitter></shape>')

out.write_text(f"""<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="8"/></integrator>
<sensor type="perspective">
  <float name="fov" value="35"/>
  <transform name="to_world"><lookat origin="{', '.join(map(str, origin))}" target="{', '.join(map(str, origin + forward))}" up="{', '.join(map(str, up))}"/></transform>
  <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
  <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/>
    <rfilter type="tent"/><string name="pixel_format" value="rgb"/></film>
</sensor>
{chr(10).join(BSDFS.values())}
{chr(10).join(shapes)}
</scene>
""")
print(f"wrote {out}: {len(shapes)} shapes")
