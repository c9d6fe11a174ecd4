"""Writing a scene description in pathtrace's TOML format (docs/scene-format.md): what
`pathtrace convert` produces. Meshes read from files stay references to them (with the transform
as a matrix); shapes a file generated (rectangles, cubes, disks) are written out inline."""

import json
import os
from pathlib import Path

import numpy as np

from pathtrace.materials import BSDFS
from pathtrace.errors import UserError
from pathtrace.scene.description import Scene
from pathtrace.scene.toml_reader import MAX_INLINE


def _value(v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)            # a TOML basic string is a JSON string
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return str(np.float32(v))       # the shortest text that reads back as the same float32
    return "[" + ", ".join(_value(x) for x in v) + "]"


def _inline(table: dict) -> str:
    return "{ " + ", ".join(f"{k} = {_value(v)}" for k, v in table.items()) + " }"


def _color(c):
    c = [float(x) for x in np.asarray(c, np.float64).reshape(-1)]
    return c[0] if len(set(c)) == 1 else c


def material_table(material) -> dict:
    """A material as the TOML reader reads it back."""
    if material.type == "black":
        return {"type": "emitter", "Le": _color(material.emission)}
    bsdf = BSDFS[material.type]
    table = {"type": material.type}
    for p in bsdf.params:
        if p.kind == "name":
            continue
        v = material.params[p.name]
        table[p.name] = _color(v) if p.kind == "color" else bool(v) if p.kind == "bool" else float(v)
    if np.any(material.emission > 0):
        table["Le"] = _color(material.emission)
    if material.twosided:
        table["twosided"] = True
    return table


def scene_toml(scene: Scene, out: Path) -> str:
    """The TOML text of a scene, its file references relative to `out`'s folder."""
    def rel(path):
        return os.path.relpath(Path(path).resolve(), Path(out).resolve().parent)

    s, cam, env = scene.settings, scene.camera, scene.environment
    lines = [f"# {scene.name}, converted by pathtrace convert", "",
             "[camera]", f"eye = {_value(cam.eye.tolist())}", f"look_at = {_value(cam.look_at.tolist())}",
             f"up = {_value(cam.up.tolist())}", f"vfov = {_value(cam.vfov)}", "",
             "[environment]"]
    if env.source == "constant":
        lines.append(f"color = {_value(_color(env.image[0, 0]))}")
    else:
        lines.append(f"map = {_value(rel(env.source))}")
    lines += [f"intensity = {_value(env.intensity)}", f"rotation = {_value(env.rotation)}", "",
              "[render]", f"width = {s.width}", f"height = {s.height}", f"spp = {s.spp}",
              f"max_depth = {s.max_depth}", f"russian_roulette = {_value(s.russian_roulette)}",
              f"seed = {s.seed}", f"nee = {_value(s.nee)}", "", "[materials]"]
    names = {}
    for row in range(len(scene.materials)):
        names[row] = scene.materials.name_of(row) or f"material{row}"
        lines.append(f"{json.dumps(names[row])} = {_inline(material_table(scene.materials.get(row)))}")
    for i, sphere in enumerate(scene.spheres):
        lines += ["", "[[spheres]]", f"name = {_value(scene.sphere_name(i))}",
                  f"center = {_value(sphere[:3].tolist())}", f"radius = {_value(sphere[3])}",
                  f"material = {_value(names[int(scene.sphere_material[i])])}"]
    for mesh in scene.meshes:
        lines += ["", "[[meshes]]", f"name = {_value(mesh.name)}", f"material = {_value(names[mesh.material])}"]
        if mesh.file is not None:
            lines += [f"file = {_value(rel(mesh.file.path))}", f"matrix = {_value(mesh.file.matrix.tolist())}"]
            if mesh.file.face_normals:
                lines.append("face_normals = true")
            if mesh.file.flip_normals:
                lines.append("flip_normals = true")
        else:
            if len(mesh.vertices) > MAX_INLINE or len(mesh.faces) > MAX_INLINE:
                raise UserError(f"{mesh.name}: {len(mesh.faces)} triangles is too many to write inline")
            lines += [f"vertices = {_value(mesh.vertices.astype(np.float64).tolist())}",
                      f"faces = {_value(mesh.faces.tolist())}"]
    return "\n".join(lines) + "\n"
