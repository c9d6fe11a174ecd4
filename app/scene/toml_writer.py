"""Writing a scene description in pathtrace's TOML format (docs/scene-format.md): what
`pathtrace convert` produces. Meshes read from files stay references to them (with the transform
as a matrix); shapes a file generated (rectangles, cubes, disks) are written out inline."""

import json
import os
from pathlib import Path

import numpy as np

from pathtrace.materials import BSDFS
from pathtrace.materials.table import component_rows
from pathtrace.errors import UserError
from pathtrace.resources import resource_dir
from pathtrace.scene.description import Scene
from pathtrace.scene.toml_values import MAX_INLINE
from pathtrace.shapes import SHAPES, TextureUV
from pathtrace.textures import Texture



def _unique_name(preferred, fallback: str, taken: set) -> str:
    """`preferred` where it is given and not taken, else `fallback`, numbered where that is taken
    too; noted in `taken`."""
    name = preferred if preferred and preferred not in taken else fallback
    k = 2
    while name in taken:
        name, k = f"{fallback}_{k}", k + 1
    taken.add(name)
    return name


def _value(v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)            # a TOML basic string is a JSON string
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return str(np.float32(v))       # the shortest text that reads back as the same float32
    if isinstance(v, dict):
        return _inline(v)
    return "[" + ", ".join(_value(x) for x in v) + "]"


def _inline(table: dict) -> str:
    return "{ " + ", ".join(f"{k} = {_value(v)}" for k, v in table.items()) + " }"


def _color(c):
    c = [float(x) for x in np.asarray(c, np.float64).reshape(-1)]
    return c[0] if len(set(c)) == 1 else c


def material_table(material, texture_names: dict = {}) -> dict:
    """A material as the TOML reader reads it back; its textures by their names in
    texture_names (id(Texture) -> name)."""
    def value(v, kind):
        if isinstance(v, Texture):
            return texture_names[id(v)]
        return _color(v) if kind == "color" else bool(v) if kind == "bool" else float(v)
    if material.type == "black":
        table = {"type": "emitter", "Le": value(material.emission, "color")}
        if material.emits_back:
            table["emits_back"] = True
        if material.masked:
            table["opacity"] = value(material.opacity, "number")
        return table
    bsdf = BSDFS[material.type]
    table = {"type": material.type}
    for p in bsdf.params:
        # what resolves into other parameters is not kept: a name, principled's specular (its eta)
        if p.kind != "name" and p.into is None:
            table[p.name] = value(material.params[p.name], p.kind)
    if isinstance(material.emission, Texture) or np.any(material.emission > 0):
        table["Le"] = value(material.emission, "color")
        if material.emits_back:
            table["emits_back"] = True
    if material.twosided:
        table["twosided"] = True
    if material.masked:
        table["opacity"] = value(material.opacity, "number")
    for key in ("normal_map", "bump_map"):
        if getattr(material, key) is not None:
            table[key] = value(getattr(material, key), "color")
            if material.perturbation != "mitsuba":
                table["perturbation"] = material.perturbation
    if material.components:
        table["bsdfs"] = [material_table(c, texture_names) for c in material.components]
    return table


def texture_table(texture: Texture, names: dict, rel) -> dict:
    """A texture as the TOML reader reads it back: its inputs by name, a bitmap's file relative
    to the output, its uv transform as a matrix."""
    table = {"type": texture.type}
    for key in texture.kind.inputs:
        v = texture.params[key]
        table[key] = names[id(v)] if isinstance(v, Texture) else _color(v)
    if texture.type == "constant":
        table["value"] = _color(texture.params["value"])
    if texture.type == "bitmap":
        image = texture.params["image"]
        if not image.path:
            raise UserError(f"texture {texture.name or ''}: an image made in memory has no file to refer to")
        table["file"] = rel(image.path)
        if image.linear and image.texels.dtype == np.uint8:
            table["raw"] = True
        table["filter"], table["wrap"] = texture.params["filter"], texture.params["wrap"]
    m = texture.params.get("to_uv")
    if m is not None and not np.allclose(m, np.eye(3)):
        table["uv_matrix"] = np.asarray(m, np.float64).tolist()
    return table


def filter_table(f) -> dict:
    table = {"type": f.name, "radius": f.radius}
    if f.name == "gaussian":
        table["stddev"] = f.stddev
    return table


def _plain(value, rel):
    """A light's parameter as TOML holds it: arrays as lists of floats, an image as its file's
    name relative to the scene (rel)."""
    if hasattr(value, "texels"):
        return rel(value.path)
    return np.asarray(value, np.float64).tolist() if isinstance(value, np.ndarray) else value


def _shipped_map(source: str, out: Path) -> bool:
    """Whether `source` is a map pathtrace ships, which no file beside `out` hides by its name."""
    shipped = (resource_dir("assets") / "envmaps").resolve()
    return Path(source).resolve().parent == shipped and not (Path(out).parent / Path(source).name).exists()


def scene_toml(scene: Scene, out: Path) -> str:
    """The TOML text of a scene, its file references relative to `out`'s folder."""
    def rel(path):
        return os.path.relpath(Path(path).resolve(), Path(out).resolve().parent)

    s, cam, env = scene.settings, scene.camera, scene.environment
    lines = [f"# {scene.name}, converted by pathtrace convert", "", "[camera]"]
    lines += [f"{key} = {_value(value)}" for key, value in cam.toml().items()]
    medium_names = _medium_names(scene.media)
    if scene.camera_medium >= 0:
        lines.append(f"medium = {_value(medium_names[scene.camera_medium])}")
    lines += ["", "[environment]"]
    if env.source == "constant":
        lines.append(f"color = {_value(_color(env.image[0, 0]))}")
    else:
        # a shipped map by its bare name, which the TOML reader finds wherever pathtrace is
        # installed (a path into the environment would break when it is made again)
        lines.append(f"map = {_value(Path(env.source).name if _shipped_map(env.source, out) else rel(env.source))}")
        if env.rows != "centres":
            lines.append(f"rows = {_value(env.rows)}")
    if tuple(env.up) != (0.0, 1.0, 0.0):
        lines.append(f"up = {_value(list(env.up))}")
    if env.mirrored:
        lines.append("mirrored = true")
    lines += [f"intensity = {_value(env.intensity)}", f"rotation = {_value(env.rotation)}", "",
              "[render]", f"width = {s.width}", f"height = {s.height}", f"spp = {s.spp}",
              f"max_depth = {s.max_depth}", f"russian_roulette = {_value(s.russian_roulette)}",
              f"seed = {s.seed}", f"nee = {_value(s.nee)}",
              f"filter = {_inline(filter_table(s.filter))}", f"light_sampler = {_value(s.light_sampler)}",
              f"integrator = {_value(s.integrator)}", f"photon_radius = {_value(s.photon_radius)}", ""]
    for light in scene.lights:
        lines += ["[[lights]]", f"type = {_value(light.name)}"]
        lines += [f"{name} = {_value(_plain(getattr(light, name), rel))}" for name in light.fields]
        lines.append("")
    textures = scene.materials.all_textures()
    texture_names, taken = {}, set()
    for k, t in enumerate(textures):
        texture_names[id(t)] = _unique_name(t.name, f"texture{k}", taken)
    if textures:      # inputs first, so that the file reads in order
        lines.append("[textures]")
        for t in sorted(textures, key=lambda t: not t.kind.leaf):
            lines.append(f"{json.dumps(texture_names[id(t)])} = {_inline(texture_table(t, texture_names, rel))}")
        lines.append("")
    if scene.media:
        lines.append("[media]")
        for name, m in zip(medium_names, scene.media):
            table = {"sigma_a": _color(m.sigma_a), "sigma_s": _color(m.sigma_s), "g": float(m.g)}
            lines.append(f"{json.dumps(name)} = {_inline(table)}")
        lines.append("")
    lines.append("[materials]")
    names, taken, given = {}, set(), {}
    for name, row in scene.materials.names.items():
        given.setdefault(row, name)                 # (as name_of, without a search per row)
    components = set(component_rows(scene.materials.rows).tolist())    # written inside their blends
    rows = [row for row in range(len(scene.materials)) if row not in components]
    # a file's names may be any, "material0" too: each row a key of its own (a second was invalid
    # TOML), the named rows keeping their names first
    for row in sorted(rows, key=lambda row: row not in given):
        names[row] = _unique_name(given.get(row), f"material{row}", taken)
    for row in rows:
        lines.append(f"{json.dumps(names[row])} = {_inline(material_table(scene.materials.get(row), texture_names))}")
    for i, sphere in enumerate(scene.spheres):
        lines += ["", "[[spheres]]", f"name = {_value(scene.sphere_name(i))}",
                  f"center = {_value(sphere[:3].tolist())}", f"radius = {_value(sphere[3])}",
                  f"material = {_value(names[int(scene.sphere_material[i])])}"]
        lines += _interface_lines(scene.sphere_media[i] if scene.sphere_media else None, medium_names)
    for mesh in scene.meshes:
        lines += ["", "[[meshes]]"] + _mesh_lines(mesh, names, medium_names, rel)
    for shape in scene.shapes:
        lines += ["", "[[shapes]]"] + _shape_lines(shape, names, medium_names)
    if scene.instances is not None:
        for o in scene.instances.objects:
            for mesh in o.meshes:
                lines += ["", f"[[objects.{json.dumps(o.name)}.meshes]]"] + _mesh_lines(mesh, names, medium_names, rel)
        for k in range(len(scene.instances)):
            lines += ["", "[[instances]]", f"object = {_value(scene.instances.objects[scene.instances.object[k]].name)}",
                      f"matrix = {_value(scene.instances.to_world[k].tolist())}"]
    return "\n".join(lines) + "\n"


def _mesh_lines(mesh, names: dict, medium_names: list, rel) -> list:
    """The keys of a mesh's table: its name, material, media, and its file or its geometry."""
    lines = [f"name = {_value(mesh.name)}", f"material = {_value(names[mesh.material])}"]
    lines += _interface_lines(mesh.media, medium_names)
    if mesh.file is not None:
        lines += [f"file = {_value(rel(mesh.file.path))}", f"matrix = {_value(mesh.file.matrix.tolist())}"]
        if mesh.file.face_normals:
            lines.append("face_normals = true")
        if mesh.file.flip_normals:
            lines.append("flip_normals = true")
        if mesh.file.smooth:
            lines.append("smooth = true")
    else:
        if len(mesh.vertices) > MAX_INLINE or len(mesh.faces) > MAX_INLINE:
            raise UserError(f"{mesh.name}: {len(mesh.faces)} triangles is too many to write inline")
        lines += [f"vertices = {_value(mesh.vertices.astype(np.float64).tolist())}",
                  f"faces = {_value(mesh.faces.tolist())}"]
        if mesh.uvs is not None:
            lines.append(f"uvs = {_value(mesh.uvs.astype(np.float64).tolist())}")
    return lines


def _shape_lines(shape, names: dict, medium_names: list) -> list:
    """The keys of an analytic shape's table (toml_reader: shape)."""
    lines = [f"kind = {_value(shape.kind)}", f"name = {_value(shape.name)}",
             f"material = {_value(names[shape.material])}"]
    lines += _interface_lines(shape.media, medium_names)
    for name, v in SHAPES[shape.kind].file_values(shape.params).items():
        lines.append(f"{name} = {_value(v)}")
    lines.append(f"matrix = {_value(np.asarray(shape.to_world, np.float64).tolist())}")
    lines += (["flip = true"] if shape.flip else []) + (
        [f"texture_uv = {_value(shape.texture_uv.value)}"] if shape.texture_uv is not TextureUV.KIND else [])
    return lines


def _medium_names(media: list) -> list:
    """Unique names for the [media] table, the media's own where they are unique."""
    names, taken = [], set()
    for k, m in enumerate(media):
        name = m.name if m.name and m.name not in taken else f"medium{k}"
        names.append(name)
        taken.add(name)
    return names


def _interface_lines(interface, medium_names: list) -> list:
    """A shape's interior and exterior media (a side of vacuum left out); nothing for a shape
    that bounds none."""
    if interface is None:
        return []
    return [f"{key} = {_value(medium_names[row])}"
            for key, row in (("interior", interface.interior), ("exterior", interface.exterior)) if row >= 0]
