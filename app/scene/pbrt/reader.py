"""The pbrt-v4 scene reader: the scene's directives (pbrt-v4's file format, "pbrt-v4 User's
Guide" and its src/pbrt/scene.cpp) mapped onto pathtrace's scene description, on the graphics
state (state.py) and the scene-wide options (options.py).

Conventions, each as pbrt-v4 has it:
- a triangle's front is its winding's side (turned by `ReverseOrientation`), or where it has
  normals `N`, their side; an area light emits from its front unless `twosided`;
- texture coordinates: pbrt looks images up at (u, 1 - v); the reader turns every mesh's v
  round once, to pathtrace's (Mitsuba's) convention, and maps textures accordingly;
- filenames are relative to the main file's folder, `Include`d files' too;
- media: a shape bounds the current MediumInterface's inside (behind its front) and outside
  media where they differ, else none (a ray keeps its medium across it); the camera is in the
  outside medium current at `Camera`; `interface` shapes are null surfaces.
Instances (`ObjectBegin`/`ObjectInstance`) are the scene's objects and instances
(app/scene/instances.py: a two-level BVH, or world-space copies where they are few); spheres in
an object, analytic shapes, are copied into world space at each instance."""

import gc
import gzip
import os
import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from pathtrace.scene.environment import Environment
from pathtrace.errors import UserError, cut, warn
from pathtrace.io.files import check_regular_file
from pathtrace import filters
from pathtrace import parameters as declared
from pathtrace.lights import DELTA_LIGHTS
from pathtrace.lights.area import DiffuseAreaLight, pbrt_radiance
from pathtrace.materials.surface import OPACITY
from pathtrace.scene.media import Medium, MediumInterface
from pathtrace.scene import transform
from pathtrace.scene.description import Mesh, Scene, SceneBuilder
from pathtrace.scene import settings
from pathtrace.scene.known_names import Unread, refuse_unknown_type
from pathtrace.scene.meshes import MAX_COORDINATE, MeshFiles, check_mesh, place_mesh
from pathtrace.scene.mesh_shapes import MESH_SHAPES, MeshSource
from pathtrace.scene.pbrt.materials import MaterialMapper, make
from pathtrace.scene.pbrt.options import OPTION_DIRECTIVES, OptionDirectives
from pathtrace.scene.pbrt.state import (MAX_FILE_BYTES, MAX_INCLUDE_DEPTH, STATE_DIRECTIVES, GraphicsStateDirectives,
                                        check_block)
from pathtrace.scene.pbrt.tokens import Tokens, parameters, string
from pathtrace.shapes import SHAPES, Shape

LIGHTS_BY_NAME = declared.by_format(DELTA_LIGHTS.values(), "pbrt")
MESHES_BY_NAME = declared.by_format(MESH_SHAPES.values(), "pbrt")
# a plymesh shape and its file name, as MeshFiles reads them ahead (PbrtReader.named_mesh_files)
_PLYMESH = re.compile(r'Shape\s+"plymesh"')
_FILENAME = re.compile(r'"string\s+filename"\s*\[?\s*"([^"]*)"')


class PbrtReader(GraphicsStateDirectives, OptionDirectives):
    def __init__(self, path: Path):
        super().__init__(path)
        self.named_materials = {}
        self.material_names = {}          # id(Material) -> (its MakeNamedMaterial name, which names its row,
                                          # and the Material, kept so that its id stays its own)
        self.mapper = MaterialMapper(self)
        self.builder = SceneBuilder()
        self.settings = settings.defaults("pbrt")
        self.filter = filters.format_default("pbrt")
        self.camera_params = None
        self.environment = None
        self.lights = []
        self.media = []                   # the scene's media, None where named but not yet made
        self.medium_rows = {}             # medium name -> row of self.media
        self.medium_mentions = {}         # medium name -> where it was first named
        self.null_material = make("null", {}, "")    # the interface material's, one row for all
        self.material_rows = {}
        self.default_material = None
        self.unread = Unread("pbrt")     # the parameters not read: refused or warned of
        self.mesh_files = MeshFiles()     # the plymesh shapes' files, read ahead
        self.dropped = [0, 0]             # degenerate triangles dropped, of the meshes' triangles

    # -- files --

    def degenerate(self, dropped, total):
        """check_mesh's count of a mesh's degenerate triangles, which read() reports once."""
        self.dropped[0] += dropped
        self.dropped[1] += total

    def read(self) -> Scene:
        # the cyclic garbage collector off while reading: a large file's tokens, parameters and
        # graphics states all live until the scene is built, and the collections that their
        # allocation sets off, each walking them all again, found nothing and took a third of
        # the time of reading 100,000 small directives
        collecting = gc.isenabled()
        gc.disable()
        try:
            with self.mesh_files:
                self.parse_file(self.path, "scene")
        finally:
            if collecting:
                gc.enable()
        if self.dropped[0]:
            # pbrt-v4 keeps them, but its IntersectTriangle returns no intersection for a
            # triangle of zero area (src/pbrt/shapes.h), nor does its area light sample one
            warn(f"{self.path}: dropped {self.dropped[0]} degenerate triangle(s) of zero area, of "
                 f"{self.dropped[1]} in the meshes that had any (pbrt-v4 never hits them)")
        # pbrt-v4 refuses both (BasicSceneBuilder::EndOfFiles)
        if not self.in_world:
            raise UserError(f"{self.path}: the file ends before WorldBegin (pbrt-v4 refuses it too)")
        if self.stack:
            directive, _, where = self.stack[-1]
            raise UserError(f"{where}: {directive} without its end, as the file ends (pbrt-v4 refuses it too)")
        self.settings.filter = self.filter
        for name, row in self.medium_rows.items():
            if self.media[row] is None:
                raise UserError(f"{self.medium_mentions[name]}: no medium named '{cut(name)}' (MakeNamedMedium)")
        camera_medium = self.camera_params[4] if self.camera_params else -1
        return self.builder.build(self.path.stem, camera=self.make_camera(),
                                  environment=self.environment or Environment.constant((0, 0, 0)),
                                  settings=self.settings, source=str(self.path), lights=self.lights,
                                  media=self.media, camera_medium=camera_medium)

    def parse_file(self, path: Path, where: str):
        if len(self.including) >= MAX_INCLUDE_DEPTH:
            raise UserError(f"{where}: Include nested more than {MAX_INCLUDE_DEPTH} deep")
        check_regular_file(path, where, "scene file", MAX_FILE_BYTES)
        real = os.path.realpath(path)
        if real in self.including:
            raise UserError(f"{where}: '{cut(str(path), 100)}' includes itself")
        try:
            data = path.read_bytes()
            if data[:2] == b"\x1f\x8b":
                data = gzip.decompress(data)
            text = data.decode("utf-8")
        except (OSError, EOFError, gzip.BadGzipFile) as e:
            raise UserError(f"{where}: {path}: cannot be read ({e})") from None
        except UnicodeDecodeError as e:
            raise UserError(f"{path}: not a text file (byte {e.start} is not UTF-8)") from None
        self.including.append(real)
        tokens = Tokens(text, path)
        self.mesh_files.add(self.named_mesh_files(text, tokens))
        while True:
            kind, name, offset = tokens.next()
            if kind == "end":
                break
            if kind != "word":
                tokens.fail(offset, f"expected a directive, got {'a quoted string' if kind == 'string' else kind}")
            handler = DIRECTIVES.get(name)
            if handler is None:
                tokens.fail(offset, f"unknown directive '{cut(name)}'")
            check_block(self, name, tokens, offset)
            handler(self, tokens, offset)
        self.including.pop()

    def named_mesh_files(self, text: str, tokens: Tokens) -> list:
        """The (path, where) of the files that the file's plymesh shapes seem to name, in order,
        for MeshFiles to read ahead: a guess by pattern (a commented-out shape is read for
        nothing, a file named otherwise is left to shape_mesh), which shape_mesh's own read
        corrects."""
        starts = [m.start() for m in _PLYMESH.finditer(text)] + [len(text)]
        found = []
        for start, end in zip(starts, starts[1:]):
            name = _FILENAME.search(text, start, min(end, start + 4096))
            if name:
                found.append((self.resolve(name.group(1)), f"{tokens.where(start)}: filename"))
        return found

    def unused(self, params, category, kind):
        """The parameters of a directive of pbrt-v4's `category` ("shape") and `kind` ("sphere")
        that the reader did not read: refused where pbrt-v4 does not know them either, else
        warned of, once per name in a file (app/scene/known_names.py)."""
        label = f"{kind} {'area light' if category == 'arealight' else category}"
        for p in params.unused():
            message = self.unread.check(params.tokens.where(p.offset), f"{category} {kind}", label, p.name,
                                        params.tokens.name)
            if message:
                warn(message)

    def _material(self, tokens, offset):
        kind = string(tokens, "Material")
        params = parameters(tokens)
        self.state.material = self.mapper.material(kind, params, tokens.where(offset))
        self.unused(params, "material", kind)

    def _make_named_material(self, tokens, offset):
        name = string(tokens, "MakeNamedMaterial")
        params = parameters(tokens)
        kind = params.string("type")
        if kind is None:
            tokens.fail(offset, f"MakeNamedMaterial '{cut(name)}' needs a \"string type\"")
        self.named_materials[name] = self.mapper.material(kind, params, tokens.where(offset))
        self.material_names[id(self.named_materials[name])] = (name, self.named_materials[name])
        self.unused(params, "material", kind)

    def named_material(self, name, where):
        if name not in self.named_materials:
            raise UserError(f"{where}: no material named '{cut(name)}'")
        return self.named_materials[name]

    def _named_material(self, tokens, offset):
        self.state.material = self.named_material(string(tokens, "NamedMaterial"), tokens.where(offset))

    def _texture(self, tokens, offset):
        name = string(tokens, "Texture")
        kind = string(tokens, "Texture")
        cls = string(tokens, "Texture")
        params = parameters(tokens)
        self.mapper.define_texture(name, kind, cls, params, tokens.where(offset))
        self.unused(params, "texture", cls)

    def _area_light(self, tokens, offset):
        kind = string(tokens, "AreaLightSource")
        params = parameters(tokens)
        if kind != "diffuse":
            tokens.fail(offset, f"unknown area light '{cut(kind)}' (pbrt-v4 has diffuse)")
        self.state.area_light = (params, tokens.where(offset))

    def medium_row(self, name: str, where: str) -> int:
        """The row of the medium `name` ("": none, -1), which MakeNamedMedium may make later in
        the file (pbrt-v4 creates media before shapes, whatever the order)."""
        if not name:
            return -1
        if name not in self.medium_rows:
            self.medium_rows[name] = len(self.media)
            self.media.append(None)
            self.medium_mentions[name] = where
        return self.medium_rows[name]

    def _medium(self, tokens, offset):
        """MakeNamedMedium: a homogeneous medium (sigma_a, sigma_s, scale, g); pbrt-v4's grid
        and cloud media are none of pathtrace's yet."""
        name = string(tokens, "MakeNamedMedium")
        params = parameters(tokens)
        where = tokens.where(offset)
        kind = params.string("type")
        if kind is None:
            tokens.fail(offset, f"MakeNamedMedium '{cut(name)}' needs a \"string type\"")
        if name in self.medium_rows and self.media[self.medium_rows[name]] is not None:
            tokens.fail(offset, f"a second medium named '{cut(name)}'")
        row = self.medium_row(name, where)
        if kind != "homogeneous":
            params.ignore()
            warn(f"{where}: pathtrace has homogeneous media only; the {cut(kind)} medium '{cut(name)}' "
                 "is rendered as vacuum")
            self.media[row] = Medium(name, np.zeros(3), np.zeros(3))
            return
        values = self.read_declared(Medium, params, where)
        try:
            self.media[row] = Medium.from_values(name, values)
        except ValueError as e:
            self.mapper.fail(params, where, e)
        self.unused(params, "medium", "homogeneous")

    def medium_interface(self, where) -> MediumInterface | None:
        """The media the current shape bounds, or None where both sides are the same (pbrt-v4:
        no transition, the ray keeps its medium)."""
        inside, outside = self.state.media
        if inside == outside:
            return None
        return MediumInterface(self.medium_row(inside, where), self.medium_row(outside, where))

    # -- instancing --

    def _object_instance(self, tokens, offset):
        name = string(tokens, "ObjectInstance")
        if self.current_object is not None:
            tokens.fail(offset, "ObjectInstance inside ObjectBegin (pbrt-v4 has no nested instances)")
        if name not in self.objects:
            tokens.fail(offset, f"no object named '{cut(name)}'")
        if self.singular():
            warn(f"{tokens.where(offset)}: the current transform is singular (it flattens the instance); "
                 "pathtrace leaves the instance out")
            return
        if self.objects[name] is None:
            self.make_object(name)
        self.builder.add_instance(self.objects[name], self.state.ctm, tokens.where(offset))

    def make_object(self, name: str):
        """The object `name`, its shapes made now, each in the graphics state it was read in."""
        self.objects[name] = self.builder.add_object(name)
        saved = self.state, self.current_object
        self.current_object = name
        try:
            for kind, params, where, state in self.object_shapes.pop(name):
                self.state = state
                self.add_shape(kind, params, where)
        finally:
            self.state, self.current_object = saved

    # -- shapes --

    def material_row(self, emission=None, alpha=1.0, emits_back=False):
        """The row of the current material, with a shape's emission (from both sides where
        emits_back) and alpha (a row of its own where either is given)."""
        material = self.state.material
        if isinstance(material, str):
            # pbrt-v4's default, one for the file (made again in each attribute block, it
            # would add a row per shape)
            if self.default_material is None:
                self.default_material = make("diffuse", {"rho_d": np.full(3, 0.5)}, "")
            material = self.default_material
        if material is None:              # pbrt's interface: no surface, only a boundary of media
            material = self.null_material
        if alpha is not None and not (isinstance(alpha, float) and alpha == 1.0):
            material = replace(material, opacity=alpha)
            if emission is None:
                return self.builder.material(material)
        if emission is not None:
            return self.builder.material(replace(material, emission=emission, emits_back=emits_back))
        if id(material) not in self.material_rows:
            row = self.builder.materials.add(material, self.material_names.get(id(material), (None,))[0])
            self.material_rows[id(material)] = (row, material)
        return self.material_rows[id(material)][0]

    def check_extent(self, vertices, where):
        if np.any(np.abs(vertices) > MAX_COORDINATE):
            raise UserError(f"{where}: the shape reaches beyond {MAX_COORDINATE:g}, which float32 cannot trace")

    def _shape(self, tokens, offset):
        kind = string(tokens, "Shape")
        params = parameters(tokens)
        where = tokens.where(offset)
        refuse_unknown_type("pbrt", "shape", kind, where)
        if self.current_object is not None:
            self.object_shapes[self.current_object].append((kind, params, where, self.state.copy()))
        else:
            self.add_shape(kind, params, where)

    def add_shape(self, kind, params, where):
        media = self.medium_interface(where)
        if self.state.material is None and self.state.area_light is not None:
            # pbrt-v4 makes no area light of a shape without a material (src/pbrt/scene.cpp, the
            # area lights' loop: 'Ignoring area light specification for shape with "interface"
            # material.')
            warn(f"{where}: pbrt-v4 makes no area light of a shape of the interface material; "
                 "neither does pathtrace, and the shape does not emit")
        if self.state.material is None and media is None:
            params.ignore()
            self.once(("interface", where), f"{where}: a shape of the interface material that bounds no "
                                            "medium is nothing; pathtrace leaves it out")
            return
        singular = self.singular()
        shape = None if singular or kind not in SHAPES else self.analytic_shape(kind, params, media, where)
        if singular or (shape is not None and SHAPES[kind].too_flat(shape)):
            params.ignore()
            # pbrt-v4 would carry NaN normals and a NaN inverse: flattened to nothing (or, for
            # an analytic shape, too near it for the inverse the kernels intersect with), the
            # shape is left out (as degenerate triangles are)
            warn(f"{where}: the current transform is singular (it flattens the shape); pathtrace leaves the shape out")
            return
        mesh = self.shape_mesh(kind, params, where) if shape is None else (None, None, None, None, "")
        if mesh is None:
            return
        vertices, faces, normals, uvs, source = mesh
        parts, twosided = self.area_emission(vertices, faces, where,
                                             None if shape is None else SHAPES[kind].area(shape.params))
        if self.current_object is not None and parts[0][1] is not None:
            warn(f"{where}: pbrt-v4 has no area lights in instances; this shape does not emit")
            parts = [(None, None)]
        alpha = self.read_declared((OPACITY,), params, where).get("opacity", 1.0)
        self.unused(params, "shape", kind)
        group = None if self.current_object is None else self.objects[self.current_object]
        if shape is not None:
            shape.material = self.material_row(parts[0][1], alpha, twosided)
            return self.builder.add_to(group, shape)
        name = Path(source).stem if source else f"{kind} {len(self.builder.meshes)}"
        for subset, emission in parts:
            row = self.material_row(emission, alpha, twosided)
            part = faces if subset is None else faces[subset]
            # no MeshFile: the file's faces were turned and its uvs flipped, which a converted
            # scene's reference to the file could not say (convert writes the mesh anew)
            self.builder.add_to(group, Mesh(name, vertices, part, normals, row, source, None, uvs, media), where)

    def analytic_shape(self, kind, params, media, where) -> Shape:
        """An analytic shape (app/shapes/), its parameters read by their pbrt-v4 names
        (ShapeParameter.pbrt), its material set by add_shape. Its front is the kind's normal
        moved by the transform, turned by ReverseOrientation and by a transform that swaps
        handedness (pbrt-v4's Disk and Cylinder: reverseOrientation ^ transformSwapsHandedness)."""
        k = SHAPES[kind]
        values = k.params_from(self.read_declared(k, params, where))
        problem = k.check(values)
        if problem:
            raise UserError(f"{where}: the {kind}'s {problem}")
        m = self.state.ctm
        values, local, texture_uv = k.from_pbrt(values)
        shape = Shape(self.builder.shape_name(kind), kind, values, m @ local, 0,
                      flip=self.state.reverse != transform.flips_handedness(m), texture_uv=texture_uv, media=media)
        lo, hi = shape.bounds(k)
        self.check_extent(np.abs(np.array([lo, hi])), where)
        return shape

    def shape_mesh(self, kind, params, where):
        """(vertices, faces, normals, uvs, file) in world space of a mesh shape (app/scene/mesh_shapes.py)
        by its declared pbrt-v4 names, fronts as pbrt has them and texture v turned round; None
        for a shape pathtrace leaves out."""
        k = MESHES_BY_NAME.get(kind)
        if k is None:
            params.ignore()
            warn(f"{where}: pathtrace has no {kind} shape; it leaves it out")
            return None
        values = self.read_declared(k, params, where)

        def read(name):
            path = self.resolve(name)
            return self.mesh_files.read(path, f"{where}: filename", self.degenerate), str(path)
        try:
            (vertices, faces, normals, uvs), source, _ = k.triangles(values, MeshSource(
                read, lambda *mesh: check_mesh(*mesh, where, degenerate=self.degenerate),
                lambda text: warn(f"{where}: {text}")))
        except ValueError as e:      # a problem of the whole shape names its directive, as Mitsuba's reader does
            self.mapper.fail(params, f'{where}: Shape "{kind}"', e, k.parameters)
        if len(faces) == 0:
            warn(f"{where}: every triangle of the {kind} is degenerate (pbrt-v4 intersects none of them); "
                 "pathtrace leaves the shape out")
            return None
        uvs = None if uvs is None else np.column_stack([uvs[:, 0], 1 - uvs[:, 1]])
        return *place_mesh(vertices, faces, normals, self.state.ctm, self.state.reverse, True, where)[:3], uvs, source

    def read_declared(self, kind, params, where, given=None) -> dict:
        """The values of the parameters that a type `kind` declares (app/parameters.py), or of a
        tuple of Parameters, that a directive gives, converted and in range; of what pbrt-v4's
        kind has and pathtrace has not (`unsupported`), a warning of each given where the kind
        says why. A name declared with its type ("string filename") is one value of that type,
        as pbrt-v4 reads it: another is a parameter pbrt-v4 leaves unused, and refuses; a bare
        name is taken as the file writes it. `given` (app/parameters.py: read) is filled with
        the values by pbrt-v4's names."""
        fields = kind if isinstance(kind, tuple) else kind.parameters
        for key, why in ({} if isinstance(kind, tuple) else kind.unsupported.get("pbrt", {})).items():
            expected, _, name = key.rpartition(" ")
            if params.type_of(name):
                params.get(name, (expected,), 1) if expected else params.get(name, (params.type_of(name),), 0)
                if why:
                    warn(f"{params.where(name)}: {why}; ignored")
        try:
            values = declared.read(fields, "pbrt", lambda p, name: self.mapper.parameter(params, p, name), given)
            error = declared.out_of_range(fields, values)
            if error:
                raise error
        except ValueError as e:
            self.mapper.fail(params, where, e, fields)
        return values

    def area_emission(self, vertices, faces, where, area=None):
        """The emitted radiance of a shape under an AreaLightSource, as [(faces, radiance)]
        (app/lights/area.py: pbrt_radiance; faces an index array of the mesh's, or None for
        all), and whether it emits from both sides; [(None, None)] where the shape is no light."""
        if self.state.area_light is None or self.state.material is None:
            return [(None, None)], False
        params, light_where = self.state.area_light
        given = {}
        self.read_declared(DiffuseAreaLight, params, light_where, given)
        try:
            parts = pbrt_radiance(given, vertices, faces, area, lambda text: warn(f"{light_where}: {text}"))
        except ValueError as e:
            self.mapper.fail(params, light_where, e)
        self.unused(params, "arealight", "diffuse")
        return parts, given["twosided"]

    # -- lights --

    def _light(self, tokens, offset):
        """LightSource: the infinite light (the environment), or a delta light of
        pathtrace.lights by its declared pbrt-v4 names, its points and vectors in the CTM."""
        kind = string(tokens, "LightSource")
        params = parameters(tokens)
        where = tokens.where(offset)
        m = self.state.ctm
        if kind == "infinite":
            self.infinite_light(params, where)
            self.unused(params, "light", "infinite")
            return
        cls = LIGHTS_BY_NAME.get(kind)
        if cls is None:
            refuse_unknown_type("pbrt", "light", kind, where)
            params.ignore()
            warn(f"{where}: pathtrace has no {kind} light; it leaves it out")
            return
        if self.singular() and any(p.kind == "vector" for p in cls.parameters):
            # its directions flattened (or NaN in pbrt-v4), as a shape's surface: left out as a shape is
            params.ignore()
            warn(f"{where}: the current transform is singular (it flattens the light's directions); "
                 "pathtrace leaves the light out")
            return
        values = self.read_declared(cls, params, where)
        for p in cls.parameters:
            if p.name in values and p.kind in ("point", "vector"):
                v = np.asarray(values[p.name], np.float64)
                values[p.name] = transform.transform_points(m, v[None])[0] if p.kind == "point" else m[:3, :3] @ v
        try:
            light = cls.from_values(values)
        except ValueError as e:
            self.mapper.fail(params, where, e, cls.parameters)
        self.lights.append(light)
        self.unused(params, "light", kind)

    def infinite_light(self, params, where):
        """The environment, by its declared pbrt-v4 names (app/scene/environment.py): pbrt-v4's
        equal-area square map made latitude-longitude in the CTM, or L."""
        if self.environment is not None:
            warn(f"{where}: a second infinite light; pathtrace keeps the first")
            params.ignore()
            return
        if params.type_of("portal"):
            params.floats("portal", ("point3",))
            warn(f"{params.where('portal')}: pathtrace does not sample portals; the light is sampled whole")
        given = {}
        values = declared.read(Environment.parameters, "pbrt", lambda p, name: self.mapper.parameter(params, p, name),
                               given)
        try:
            self.environment = Environment.from_pbrt(values, given, self.resolve,
                                                     lambda: self.inverse(where, "an infinite light's map"), where)
        except ValueError as e:
            self.mapper.fail(params, where, e)


DIRECTIVES = {
    **STATE_DIRECTIVES,
    **OPTION_DIRECTIVES,
    "Material": PbrtReader._material,
    "MakeNamedMaterial": PbrtReader._make_named_material,
    "NamedMaterial": PbrtReader._named_material,
    "Texture": PbrtReader._texture,
    "AreaLightSource": PbrtReader._area_light,
    "LightSource": PbrtReader._light,
    "Shape": PbrtReader._shape,
    "MakeNamedMedium": PbrtReader._medium,
    "ObjectInstance": PbrtReader._object_instance,
}


def read_pbrt_file(path) -> Scene:
    return PbrtReader(Path(path)).read()
