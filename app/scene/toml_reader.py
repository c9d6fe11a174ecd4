"""Reading scene files in pathtrace's TOML format (docs/scene-format.md). Every check names
the file and the field, e.g.
    scenes/room.toml: spheres[3].radius: must be positive, got -1
"""

import os
import tomllib
from pathlib import Path

import numpy as np

from pathtrace import cameras, filters, parameters
from pathtrace.filters import PixelFilter
from pathtrace.lights import DELTA_LIGHTS
from pathtrace.rendering.choices import RUSSIAN_ROULETTE
from pathtrace.scene.environment import Environment
from pathtrace.errors import UserError, short, with_article
from pathtrace.materials import BSDFS, Material
from pathtrace.materials.surface import SURFACE, dressed
from pathtrace.materials.table import PERTURBATIONS, blend
from pathtrace.scene.media import Medium, MediumInterface
from pathtrace.resources import resource_dir
from pathtrace.scene.description import Mesh, MeshFile, RenderSettings, Scene, SceneBuilder
from pathtrace.scene.settings import RENDER
from pathtrace.scene.meshes import MAX_COORDINATE, MeshFiles, check_mesh, place_mesh
from pathtrace.scene.mesh_shapes import MESH_SHAPES, MeshSource
from pathtrace.scene.toml_values import TomlValues, as_toml
from pathtrace.shapes import SHAPES, Shape, TextureUV
from pathtrace.shapes.shape import MIN_DETERMINANT, flattened
from pathtrace.textures import TEXTURES, Texture, read_image

# the scene-file types besides the registry's: "emitter" is a black BSDF with emission, and
# "twosided" wraps another material (Mitsuba 3's plugin; `twosided = true` says the same)
FILE_TYPES = {name: b for name, b in BSDFS.items() if name != "black"}
MATERIAL_TYPES = ["emitter", "twosided", *FILE_TYPES]
FILE_MESH = MESH_SHAPES["file"]


class _Reader(TomlValues):
    def __init__(self, path: Path, label: str = None):
        """path: the scene file (meshes and maps are found beside it; its stem names the
        scene); label: how messages name the scene, the path by default."""
        super().__init__(label or str(path))
        self.path = path
        self.texture_tables = {}     # the [textures] tables, by name
        self.textures = {}           # name -> Texture, as they are read
        self.resolving = []          # the names being read (a reference cycle comes back to one)
        self.images = {}             # the images read (read_image's cache)
        self.media = {}              # name -> row of the scene's media, as [media] is read
        self.material_tables = {}    # the [materials] tables, by name (a blend's bsdfs name them)
        self.blending = []           # the named materials being read as a blend's components
        self.mesh_files = MeshFiles()  # the scene's mesh files, read ahead

    # -- textures --

    def texture_value(self, value, where) -> Texture:
        """A texture given by name (of [textures]) or as an inline table."""
        if isinstance(value, str):
            return self.named_texture(value, where)
        return self.texture(value, where)

    def named_texture(self, name, where) -> Texture:
        if name not in self.texture_tables:
            self.fail(where, f"no texture named {short(name)} (named: {', '.join(self.texture_tables) or 'none'})")
        if name in self.resolving:
            cycle = self.resolving[self.resolving.index(name):] + [name]
            self.fail(where, f"a texture reference cycle: {short(' -> '.join(cycle))}")
        if name not in self.textures:
            self.resolving.append(name)
            self.textures[name] = self.texture(self.texture_tables[name], f"textures.{name}", name)
            self.resolving.pop()
        return self.textures[name]

    def texture(self, data, where, name=None) -> Texture:
        """One texture table: its type, the type's inputs (a colour, a texture name or an inline
        table each), a bitmap's file, raw, filter and wrap, and a uv transform."""
        kind = self.kind_of(data, where, TEXTURES)
        texture_type = TEXTURES[kind]
        self.table(data, where, {"type", "uv_scale", "uv_offset", "uv_rotate", "uv_matrix",
                                 *(p.name for p in texture_type.parameters)})
        params = {"to_uv": self.uv_transform(data, where),
                  **self.declared(texture_type.parameters, data, where)}
        try:
            return Texture(kind, texture_type.complete(params), name)
        except ValueError as e:
            self.fail(where, str(e))

    def material(self, data, where) -> Material:
        """One material table: its type's parameters (`twosided` wraps another material, an
        `emitter` is black and emits), and what any material carries (app/materials/surface.py)."""
        kind = self.kind_of(data, where, MATERIAL_TYPES)
        if kind == "twosided":
            self.table(data, where, {"type", "bsdf"})
            if "bsdf" not in data:
                self.fail(where, "missing 'bsdf' (the material to make two-sided)")
            try:
                return dressed(self.material(data["bsdf"], f"{where}.bsdf"), {"twosided": True})
            except ValueError as e:           # the field is the wrapped material's, and there is no such key
                self.fail(f"{where}.bsdf", str(e).partition(": ")[2])
        if kind == "emitter":
            self.table(data, where, {"type", "Le", "emits_back", "opacity"})
            if "Le" not in data:
                self.fail(where, "missing 'Le'")
            material = Material("black")
        else:
            bsdf = FILE_TYPES[kind]
            self.table(data, where, {"type", *(p.name for p in SURFACE + bsdf.params),
                                     *(("bsdfs",) if kind == "blendbsdf" else ())})
            values = self.declared(bsdf.params, data, where)
            try:
                material = blend(values.get("weight"), self.components(data, where)) if kind == "blendbsdf" else \
                    Material(kind, bsdf.complete(values))
            except ValueError as e:
                self.fail(where, str(e))
        if data.get("perturbation", PERTURBATIONS[0]) not in PERTURBATIONS:     # its names quoted, as a file writes them
            self.not_one_of(f"{where}.perturbation", data["perturbation"], PERTURBATIONS, quoted=True)
        try:
            return dressed(material, self.declared(SURFACE, data, where))
        except ValueError as e:
            self.refuse(where, e)

    def components(self, data, where) -> tuple:
        """A blend's `bsdfs`: two materials, each a table or the name of one in [materials]."""
        given = data.get("bsdfs")
        if not isinstance(given, list) or len(given) != 2:
            self.fail(f"{where}.bsdfs", f"must be a list of two materials (tables or names), got {short(given)}")
        out = []
        for k, m in enumerate(given):
            if isinstance(m, str):
                if m not in self.material_tables:
                    self.fail(f"{where}.bsdfs[{k}]", f"no material named {short(m)} in [materials]")
                if m in self.blending:
                    self.fail(f"{where}.bsdfs[{k}]", f"a reference cycle: {short(' -> '.join(self.blending + [m]))}")
                self.blending.append(m)
                out.append(self.material(self.material_tables[m], f"materials.{m}"))
                self.blending.pop()
            else:
                out.append(self.material(m, f"{where}.bsdfs[{k}]"))
        return tuple(out)

    def declared(self, declared, data, where) -> dict:
        """The values a table gives of the `declared` parameters (app/parameters.py: read)."""
        return parameters.read(declared, "toml", lambda p, name: self.parameter(data, p, where) if name in data else None)

    def parameter(self, data, param, where):
        """One declared parameter (app/parameters.py) by its kind; one that may be a texture may
        be a name of [textures] or an inline table, whose values must lie in its range."""
        value, key = data[param.name], f"{where}.{param.name}"
        if param.kind == "texture":
            if not isinstance(value, (dict, str)):
                self.fail(key, f"must be a texture (a name or a table), got {short(value)}")
            return self.texture_value(value, key)
        # a string where a texture may stand, and no name or choice may, is a texture's name: one
        # [textures] lacks is said to be so, not that a number was expected
        names_a_texture = isinstance(value, str) and (value in self.texture_tables or not (
            getattr(param, "names", None) or param.choices or param.kind in ("name", "string")))
        if param.texture and (isinstance(value, dict) or names_a_texture):
            texture = self.texture_value(value, key)
            error = parameters.out_of_range((param,), {param.name: texture})
            if error:
                self.fail(key, f"the texture's values {str(error).partition(': ')[2]}")
            return texture
        if param.kind == "color":
            return self.color(data, param.name, where, high=param.high)
        if param.kind == "bool":
            return self.boolean(data, param.name, where, None)
        if param.kind in ("point", "vector"):
            return self.vector(data, param.name, where)
        if param.kind == "image":
            if not isinstance(value, str) or not value:
                self.fail(key, f"must be an image file name, got {short(value)}")
            return read_image(self.path.parent / value, f"{self.label}: {key}", data.get("raw") is True, self.images)
        if param.choices and not getattr(param, "names", None):
            if value not in param.choices:
                self.not_one_of(key, value, param.choices)
            return value
        names = getattr(param, "names", None)
        if isinstance(value, str) and names:
            if value not in names:
                self.fail(key, f"unknown name {short(value)} (known: {', '.join(sorted(names))})")
            return value             # BSDFType.resolve turns a material's into its number
        if param.kind == "string" and isinstance(value, str):
            return value
        if param.kind in ("name", "string"):
            self.fail(key, f"must be a {param.kind}, got {short(value)}")
        return self.number(data, param.name, where, low=param.low, high=param.high, integer=param.kind == "integer")

    def camera(self, data):
        """The [camera] table: the frame, and the parameters its type declares (app/cameras/)."""
        where = "camera"
        kind = self.kind_of(data, where, cameras.registry.toml_names(), default="perspective")
        cls = cameras.registry.toml_class(kind, data)
        values = self.typed(data, where, kind, cls, cameras.CAMERAS.values(), cls.type,
                            {"eye", "look_at", "up", "mirrored", "medium"})
        cam = cls(self.vector(data, "eye", where), self.vector(data, "look_at", where),
                  self.vector(data, "up", where, default=(0, 1, 0)),
                  mirrored=self.boolean(data, "mirrored", where, False), **values)
        try:
            cam.check()
        except ValueError as e:
            self.refuse(where, e)
        forward = cam.look_at - cam.eye
        if np.linalg.norm(forward) == 0:
            self.fail("camera.look_at", "must differ from camera.eye")
        if np.linalg.norm(cam.up) < 1e-30:
            self.fail("camera.up", f"must not be zero, got {cam.up.tolist()}")
        if np.linalg.norm(np.cross(forward, cam.up)) < 1e-9 * np.linalg.norm(forward) * np.linalg.norm(cam.up):
            self.fail("camera.up", "must not be parallel to the view direction")
        return cam

    def medium(self, data, where) -> Medium:
        """One [media] table, by Medium's declared parameters."""
        self.table(data, where, {p.name for p in Medium.parameters})
        values = self.declared(Medium.parameters, data, where)
        try:
            return Medium.from_values(where.split(".", 1)[1], values)
        except ValueError as e:
            self.refuse(where, e)

    def medium_row(self, data, key, where) -> int:
        """The row of the medium `key` names ([media]), -1 where the key is absent (vacuum)."""
        name = data.get(key)
        if name is None:
            return -1
        if name not in self.media:
            known = f" (known: {', '.join(sorted(self.media))})" if self.media else " (there is no [media] table)"
            self.fail(f"{where}.{key}", f"no medium named {short(name)}{known}")
        return self.media[name]

    def interface(self, data, where) -> MediumInterface | None:
        """The media a shape bounds (`interior`, `exterior`; one left out is vacuum), or None."""
        if "interior" not in data and "exterior" not in data:
            return None
        return MediumInterface(self.medium_row(data, "interior", where), self.medium_row(data, "exterior", where))

    def light(self, data, where):
        """One [[lights]] entry: a delta light of pathtrace.lights, by its declared parameters."""
        cls = DELTA_LIGHTS[self.kind_of(data, where, DELTA_LIGHTS)]
        self.table(data, where, {"type", *(p.name for p in cls.parameters if p.name)})
        values = self.declared(cls.parameters, data, where)
        try:
            return cls.from_values(values)
        except ValueError as e:
            self.refuse(where, e)

    def environment(self, data):
        """[environment], by its declared parameters (app/scene/environment.py): a colour or a map."""
        self.table(data, "environment", {p.name for p in Environment.parameters if p.name})
        try:
            return Environment.from_values(self.declared(Environment.parameters, data, "environment"), self.find_asset,
                                           f"{self.label}: environment")
        except ValueError as e:
            self.refuse("environment", e)

    def find_asset(self, name):
        """A map path is relative to the scene file; a bare name may also be a shipped map."""
        candidate = (self.path.parent / name)
        if _exists(candidate):
            return candidate
        shipped = resource_dir("assets") / "envmaps" / name
        return shipped if _exists(shipped) else candidate   # read_hdr says what is wrong with it

    def settings(self, data):
        """[render], by the settings' declarations (app/scene/settings.py), its filter and its Russian
        roulette (a name, or true and false)."""
        where = "render"
        self.table(data, where, {*(p.name for p in RENDER), "russian_roulette", "filter"})
        rr = data.get("russian_roulette", "throughput")
        if rr is True or rr is False:
            rr = "throughput" if rr else "off"
        if rr not in RUSSIAN_ROULETTE:
            self.not_one_of("render.russian_roulette", rr, RUSSIAN_ROULETTE, also=" (or true, false)")
        s = RenderSettings(**self.declared(RENDER, data, where), russian_roulette=rr,
                           filter=self.pixel_filter(data.get("filter", "box")))
        if not s.paths_end:
            self.fail("render.russian_roulette", "off needs a max_depth above 0, or paths never end")
        return s

    def pixel_filter(self, data) -> PixelFilter:
        """render.filter: a name or a table of a type (app/filters.py) and its parameters."""
        data = {"type": data} if isinstance(data, str) else data
        kind = self.kind_of(data, "render.filter", filters.FILTERS, default="box")
        try:
            return filters.TYPES[kind].make(self.typed(data, "render.filter", kind, filters.TYPES[kind],
                                                       filters.TYPES.values(), kind))
        except ValueError as e:
            self.refuse("render.filter", e)

    def typed(self, data, where, kind, cls, types, name, common=frozenset()) -> dict:
        """The values of a table of type `kind` (a camera's, a filter's), of the type `cls` among
        `types` (registered as `name`: a perspective camera with a lens is a thinlens one), by its
        declared parameters, besides `type` and the `common` keys: a key of another type's is
        named so, as is one the type needs and the table lacks."""
        noun, own = where.rpartition(".")[2], {"type", *common, *(p.name for p in cls.parameters if p.name)}
        for key in data:
            if key not in own and any(key in {p.name for p in c.parameters} for c in types):
                self.fail(f"{where}.{key}", f"{with_article(kind)} {noun} has no {key}")
        self.table(data, where, own)
        absent = parameters.missing(cls.parameters, data)
        if absent:
            self.fail(where, f"{with_article(name)} {noun} needs {' and '.join(repr(p.name) for p in absent)}")
        return self.declared(cls.parameters, data, where)

    def material_ref(self, builder, named, data, where):
        m = data.get("material")
        if isinstance(m, str):
            if m not in named:
                self.fail(f"{where}.material", f"no material named '{m}' in [materials]")
            return named[m]
        if m is None:
            self.fail(where, "missing 'material'")
        if not isinstance(m, dict):
            self.fail(f"{where}.material", f"must be a material's name or a table, got {short(m)}")
        return builder.material(self.material(m, f"{where}.material"))

    def shape(self, data, where, builder, rows) -> Shape:
        """A [[shapes]] entry: an analytic shape of `kind` (pathtrace.shapes.SHAPES), its kind's
        parameters by name (ShapeParameter: angles in degrees), its transform, `flip` (the front
        turned round) and `texture_uv` (its texture coordinates of the kind's (u, v): TextureUV)."""
        kind = self.kind_of(data, where, SHAPES, "kind")
        k = SHAPES[kind]
        self.table(data, where, {"kind", "material", "name", "interior", "exterior", "flip", "texture_uv", "matrix",
                                 "translate", "rotate", "scale", *(p.name for p in k.parameters)})
        values = k.params_from(self.declared(k.parameters, data, where))
        problem = k.check(values)
        if problem:
            self.fail(where, problem)
        shape = Shape(self.name(data, where, f"{kind} {where[7:-1]}"), kind, values, self.transform(data, where),
                      self.material_ref(builder, rows, data, where), self.boolean(data, "flip", where, False),
                      self.texture_uv(data, where), self.interface(data, where))
        if flattened(shape.to_world):       # (kept as its kind: read_scene adds it with keep_kind)
            self.fail(where, f"the transform shrinks or flattens the {kind} beyond what the kernels can invert "
                             f"(|det| below {MIN_DETERMINANT:g})")
        if np.any(np.abs(np.array(shape.bounds(k))) > MAX_COORDINATE):
            self.fail(where, f"the {kind} reaches beyond {MAX_COORDINATE:g}, which float32 cannot trace")
        return shape

    def texture_uv(self, data, where) -> TextureUV:
        """A shape's `texture_uv`, the TextureUV its value names (by default the kind's own)."""
        value = data.get("texture_uv", TextureUV.KIND.value)
        modes = [m.value for m in TextureUV]
        if value not in modes:
            self.not_one_of(f"{where}.texture_uv", value, modes, quoted=True)
        return TextureUV(value)

    def mesh(self, data, where, material) -> Mesh:
        """A mesh from a file, or written inline as vertices and faces (polygons of 3 or more
        corners, counter-clockwise seen from the front)."""
        self.table(data, where, {"file", "vertices", "faces", "uvs", "material", "name", "translate",
                                 "rotate", "scale", "matrix", "face_normals", "flip_normals", "smooth",
                                 "interior", "exterior"})
        values = self.declared(FILE_MESH.parameters, data, where)
        m, flip = self.transform(data, where), values.get("flip_normals", False)
        if "file" in data:
            if "vertices" in data or "faces" in data:
                self.fail(where, "give either 'file' or 'vertices' and 'faces', not both")
            try:
                (vertices, faces, normals, uvs), source, smoothed = FILE_MESH.triangles(values, MeshSource(
                    lambda name: (self.mesh_files.read(self.path.parent / name, f"{self.label}: {where}.file"),
                                  str(self.path.parent / name))))
            except ValueError as e:
                self.refuse(where, e)
            origin = MeshFile(source, m, values.get("face_normals", False), flip, smoothed)
            default_name = Path(source).stem
        else:
            vertices, faces, uvs = self.inline_geometry(data, where)
            vertices, faces, normals, uvs = check_mesh(vertices, faces, None, uvs, f"{self.label}: {where}")
            source, default_name, origin = "", f"mesh {where[7:-1]}", None
        vertices, faces, normals, _ = place_mesh(vertices, faces, normals, m, flip, False, f"{self.label}: {where}")
        return Mesh(self.name(data, where, default_name), vertices, faces, normals, material, source, origin, uvs,
                    self.interface(data, where))

    def named_mesh_files(self, meshes, objects):
        """The (path, where) of the files that [[meshes]] and then [objects] name, in the order
        they are read, for MeshFiles to read ahead (what is not a file name is left to mesh())."""
        tables = [(f"meshes[{i}]", m) for i, m in enumerate(meshes)]
        if isinstance(objects, dict):
            tables += [(f"objects.{name}.meshes[{i}]", m) for name, o in objects.items() if isinstance(o, dict)
                       and isinstance(o.get("meshes"), list) for i, m in enumerate(o["meshes"])]
        return [(self.path.parent / m["file"], f"{self.label}: {where}.file") for where, m in tables
                if isinstance(m, dict) and isinstance(m.get("file"), str) and m["file"]]

    def instances(self, data, instances, builder, rows):
        """[objects.NAME] (its `meshes`: an array of mesh tables, in the object's space) and
        [[instances]] (an `object`'s name and a transform, as a mesh's) into the builder."""
        index = {}
        for name, o in self.named_tables(data, "objects").items():
            where = f"objects.{name}"
            self.table(o, where, {"meshes"})
            meshes = o.get("meshes")
            if not isinstance(meshes, list) or not meshes:
                self.fail(f"{where}.meshes", "must be an array of mesh tables ([[objects.NAME.meshes]])")
            index[name] = builder.add_object(name)
            for i, m in enumerate(meshes):
                w = f"{where}.meshes[{i}]"
                if not isinstance(m, dict):
                    self.fail(w, f"must be a table, got {type(m).__name__}")
                mesh = self.mesh(m, w, self.material_ref(builder, rows, m, w))
                if np.any(builder.materials.rows[mesh.material]["emission"][:3] > 0):
                    self.fail(f"{w}.material", "an object's mesh cannot emit: instances have no area lights")
                builder.objects[index[name]].meshes.append(mesh)
        for i, inst in enumerate(instances):
            where = f"instances[{i}]"
            self.table(inst, where, {"object", "translate", "rotate", "scale", "matrix"})
            name = inst.get("object")
            if name not in index:
                self.fail(f"{where}.object", f"must name an entry of [objects], got {short(name)}")
            builder.add_instance(index[name], self.transform(inst, where), f"{self.label}: {where}")

    def scene(self, data) -> Scene:
        self.table(data, "top level", {"camera", "environment", "render", "textures", "materials", "spheres",
                                       "meshes", "shapes", "lights", "media", "objects", "instances"})
        builder = SceneBuilder()
        self.texture_tables = self.named_tables(data, "textures")
        for name in self.texture_tables:
            self.named_texture(name, f"textures.{name}")
        media = []
        for name, m in self.named_tables(data, "media").items():
            media.append(self.medium(m, f"media.{name}"))
            self.media[name] = len(media) - 1
        self.material_tables = self.named_tables(data, "materials")
        rows = {}
        for name, m in self.material_tables.items():
            rows[name] = builder.materials.add(self.material(m, f"materials.{name}"), name)
        spheres, meshes, shapes, instances = (self.array(data, key) for key in ("spheres", "meshes", "shapes", "instances"))
        if not (spheres or meshes or shapes or instances or "environment" in data):
            # a file that says nothing at all (a truncated one) is not a white sky
            self.fail("spheres", "the scene has no [[spheres]], [[meshes]], [[shapes]] or [[instances]] entry and no "
                                 "[environment]: nothing to render")
        lights = self.array(data, "lights")
        for i, s in enumerate(spheres):
            where = f"spheres[{i}]"
            self.table(s, where, {"center", "radius", "material", "name", "interior", "exterior"})
            center = self.vector(s, "center", where)
            radius = self.number(s, "radius", where)
            if radius <= 0:
                self.fail(f"{where}.radius", f"must be positive, got {radius}")
            if np.any(np.abs(center) + radius > MAX_COORDINATE):
                self.fail(where, f"the sphere reaches beyond {MAX_COORDINATE:g}, which float32 cannot trace")
            builder.add_sphere(center, radius, self.material_ref(builder, rows, s, where),
                               self.name(s, where, f"sphere {i}"), self.interface(s, where))
        for i, s in enumerate(shapes):
            builder.add_shape(self.shape(s, f"shapes[{i}]", builder, rows), keep_kind=True)   # as the file states it
        with MeshFiles(self.named_mesh_files(meshes, data.get("objects"))) as self.mesh_files:
            for i, m in enumerate(meshes):
                where = f"meshes[{i}]"
                if not isinstance(m, dict):
                    self.fail(where, f"must be a table, got {type(m).__name__}")
                builder.add_mesh(self.mesh(m, where, self.material_ref(builder, rows, m, where)), f"{self.label}: {where}")
            self.instances(data, instances, builder, rows)
        camera = data.get("camera", {"eye": [0, 0, 5], "look_at": [0, 0, 0]})
        return builder.build(
            self.path.stem, media=media,
            camera_medium=self.medium_row(camera, "medium", "camera") if isinstance(camera, dict) else -1,
            camera=self.camera(camera),
            environment=self.environment(data.get("environment", {})),
            settings=self.settings(data.get("render", {})), source=self.label,
            lights=[self.light(light, f"lights[{i}]") for i, light in enumerate(lights)])


def _exists(path: Path) -> bool:
    """Path.exists, but False (not an OSError) for a name too long for the file system."""
    try:
        return path.exists()
    except (OSError, ValueError):       # a name too long, or holding a NUL byte
        return False


MAX_SCENE_BYTES = 64 << 20    # a scene file; meshes go in files of their own


def read_scene_file(path) -> Scene:
    from pathtrace.io.files import check_regular_file, missing, shown
    path = Path(path)
    try:
        os.stat(path)
    except FileNotFoundError:
        raise missing(path, "scene file") from None
    except OSError as e:                 # a name too long for the file system, say
        raise UserError(f"{shown(path)}: {e.strerror}") from None
    check_regular_file(path, shown(path), "the scene file", MAX_SCENE_BYTES)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise missing(path, "scene file") from None
    except (OSError, UnicodeDecodeError) as e:
        raise UserError(f"{path}: cannot read the scene file ({e})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UserError(f"{path}: not valid TOML: {e}") from None
    except RecursionError:
        raise UserError(f"{path}: not valid TOML: arrays or tables nested too deeply") from None
    return _Reader(path).scene(data)


def read_scene_dict(data: dict, name: str = "scene", folder=".") -> Scene:
    """A scene given as the TOML format's tables in Python: dicts, lists or tuples, numbers
    (NumPy's too) and strings; NumPy arrays stand for lists. Files the scene names (meshes, maps)
    are found relative to `folder`. Messages name the scene "scene dict 'name'"."""
    return _Reader(Path(folder) / f"{name}.toml", f"scene dict {name!r}").scene(as_toml(data))


def read_material_dict(data: dict) -> Material:
    """One material given as a [materials] table of the TOML format, in Python."""
    return _Reader(Path("material.toml"), "material dict").material(as_toml(data), "material")
