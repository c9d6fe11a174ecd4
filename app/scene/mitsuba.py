"""Reading Mitsuba 3 XML scenes (the subset docs/mitsuba.md lists) into the scene description
the TOML format also produces, from the elements app/scene/mitsuba_xml.py reads. Every problem
names the file and line, e.g.
    cbox.xml:12: <float name="radius">: 'abc' is not a number
and what pathtrace cannot do (heterogeneous media, other integrators) is one warning line per
element saying what it does instead. Sizes are bounded: the XML (mitsuba_xml.py), tessellation
and the film."""

from pathlib import Path

import numpy as np

from pathtrace import cameras
from pathtrace.cameras.camera import FILM, TO_WORLD, frame_of
from pathtrace.cameras.perspective import PerspectiveCamera, vertical_fov
from pathtrace.scene.environment import Environment
from pathtrace.scene.known_names import refuse_unknown_type
from pathtrace.errors import UserError, short, warn
from pathtrace import filters
from pathtrace import parameters
from pathtrace.lights import DELTA_LIGHTS
from pathtrace.materials import BSDFS, Material
from pathtrace.materials.surface import MITSUBA_WRAPPERS, SURFACE, dressed
from pathtrace.materials.table import blend
from pathtrace.parameters import FRAME, format_names, out_of_range
from pathtrace.scene.media import Medium, MediumInterface
from pathtrace.scene.description import Mesh, MeshFile, Scene, SceneBuilder
from pathtrace.scene.mitsuba_xml import XmlScene, fail, refuse
from pathtrace.scene import settings
from pathtrace.scene.meshes import MAX_COORDINATE, MeshFiles, check_mesh, place_mesh
from pathtrace.scene.mesh_shapes import MESH_SHAPES, MeshSource
from pathtrace.shapes import SHAPES, Shape
from pathtrace.shapes.shape import MIN_DETERMINANT
from pathtrace.textures import TEXTURES, Texture, read_image
from pathtrace.textures.texture import LUMINANCE

LIGHTS_BY_NAME = parameters.by_format(DELTA_LIGHTS.values(), "mitsuba")
BSDFS_BY_NAME = parameters.by_format(BSDFS.values(), "mitsuba")
TEXTURES_BY_NAME = parameters.by_format(TEXTURES.values(), "mitsuba")
MESHES_BY_NAME = parameters.by_format(MESH_SHAPES.values(), "mitsuba")


class _Reader(XmlScene):
    """One scene: its elements (XmlScene), and the description being built."""

    def __init__(self, path: Path):
        super().__init__(path)
        self.builder = SceneBuilder()
        self.groups = {}            # id(shapegroup Node) -> its object in the builder
        self.material_rows = {}     # id(bsdf Node) -> material row
        self.textures = {}          # id(texture Node) -> Texture, so that a shared one is one
        self.images = {}            # the images read (read_image's cache)
        self.camera = None
        self.settings = settings.defaults("mitsuba")
        self.environment = None
        self.lights = []            # point, spot and directional emitters
        self.filter = None          # the film's rfilter
        self.media = []             # the scene's participating media
        self.medium_rows = {}       # id(medium Node) -> row of self.media
        self.camera_medium = -1
        self.mesh_files = MeshFiles()   # the obj and ply shapes' files, read ahead

    def color(self, props, name, default, textures=True):
        """A colour parameter: rgb, spectrum, float, or (where `textures`) a Texture; elsewhere a
        texture is replaced by its mean colour, with a warning."""
        node = props.get(name)
        if node is None:
            return np.broadcast_to(np.asarray(default, np.float64), 3).copy()
        if node.tag == "ref":
            node = self.resolve(node)
        if node.tag == "texture":
            texture = self.texture(node)
            if textures:
                return texture
            mean = texture.mean()
            warn(f"{node.where()}: a texture cannot stand here; pathtrace uses its mean colour "
                 f"({', '.join(f'{c:.3g}' for c in mean)})")
            return mean
        if node.tag == "float":
            return np.full(3, self.value(node))
        if node.tag not in ("rgb", "spectrum"):
            fail(node, f"'{name}' must be a colour (rgb, spectrum, float) or a texture")
        return self.value(node)

    def texture(self, node) -> Texture:
        """The Texture of a <texture> element: bitmap (filename, raw, filter_type, wrap_mode,
        to_uv) or checkerboard (color0, color1, to_uv), with Mitsuba 3's defaults; another type
        is replaced by a constant grey of 0.5, with a warning."""
        if id(node) in self.textures:
            return self.textures[id(node)]
        kind = node.attrs.get("type")
        props = self.properties(node)
        params = {"to_uv": self.get(props, "to_uv", np.eye(4), ("transform",))}
        if kind in TEXTURES_BY_NAME:
            params.update(parameters.read(TEXTURES_BY_NAME[kind].parameters, "mitsuba",
                                          lambda p, name: self.parameter(props, p, name)))
            absent = parameters.missing(TEXTURES_BY_NAME[kind].parameters, params)
            if absent:
                fail(node, f"a {kind} needs a {absent[0].mitsuba}")
        else:
            self.refuse_unknown("texture", node)
            warn(f"{node.where()}: pathtrace has no {kind} texture; it uses a constant grey of 0.5 instead")
            props.ignore()
            kind, params = "constant", {"value": 0.5}
        try:
            params = TEXTURES[kind].complete(params)
        except ValueError as e:
            fail(node, str(e))
        self.textures[id(node)] = Texture(kind, params, node.attrs.get("id"))
        return self.textures[id(node)]

    def refuse_unknown(self, category: str, node):
        """Refuses an element of no type, in a file of any version (Mitsuba's parser: 'missing
        required attribute "type"'), and in a Mitsuba 3 file one of a type Mitsuba 3 has not
        either, as Mitsuba 3 refuses it (app/scene/known_names.py); a file of another version
        may name that version's plugins, which are warned of and replaced as before."""
        if "type" not in node.attrs:
            fail(node, "needs a type")
        if self.version.startswith("3."):
            refuse_unknown_type("mitsuba", category, node.attrs["type"], node.where())

    # -- the scene --

    def read(self) -> Scene:
        nodes = self.elements()
        with MeshFiles(self.named_mesh_files(nodes)) as self.mesh_files:
            for node in nodes:
                # bsdfs, textures, media and shapegroups are read where they are referred to
                if node.tag in ("bsdf", "texture", "medium") or \
                        node.tag == "shape" and node.attrs.get("type") == "shapegroup":
                    continue
                handler = {"shape": self.shape, "sensor": self.sensor, "integrator": self.integrator,
                           "emitter": self.emitter}.get(node.tag)
                if handler is None:
                    warn(f"{node.where()}: not supported; pathtrace ignores it")
                else:
                    handler(node)
        self.warn_unread()
        self.settings.filter = self.filter or filters.format_default("mitsuba")
        return self.builder.build(self.path.stem, camera=self.camera or self.default_camera(),
                                  environment=self.environment or Environment.constant((0, 0, 0)),
                                  settings=self.settings, source=str(self.path), lights=self.lights,
                                  media=self.media, camera_medium=self.camera_medium)

    def named_mesh_files(self, nodes) -> list:
        """The (path, where) of the obj and ply shapes' files, in document order, for MeshFiles
        to read ahead (a file name given otherwise than as a string is left to shape())."""
        found, todo = [], list(reversed(nodes))
        while todo:
            node = todo.pop()
            if node.tag == "shape" and node.attrs.get("type") in MESH_SHAPES["file"].formats["mitsuba"]:
                filename = self.properties(node).get("filename")
                if filename is not None and filename.tag == "string" and filename.attrs.get("value"):
                    found.append((node.file.parent / filename.attrs["value"], node.where()))
            todo.extend(reversed(node.children))
        return found

    def default_camera(self):
        """Mitsuba's default sensor: at the origin, looking down +z, fov 45 on x."""
        return PerspectiveCamera((0, 0, 0), (0, 0, 1), (0, 1, 0),
                                 vertical_fov(45.0, "x", self.settings.width, self.settings.height))

    def integrator(self, node):
        kind = node.attrs.get("type")
        props = self.properties(node)
        self.settings.integrator = settings.Integrator.types["mitsuba"].get(kind, ("path",))[0]
        if kind not in settings.Integrator.types["mitsuba"]:
            self.refuse_unknown("integrator", node)
            warn(f"{node.where()}: pathtrace renders with its path tracer instead")
            props.ignore()          # that integrator's own settings: only max_depth and rr_depth are read
        self.settings.max_depth = self.declared(settings.Integrator, props, node)["max_depth"]
        rr_depth = self.get(props, "rr_depth", 5, ("integer",))
        if rr_depth != 5:
            if 0 < self.settings.max_depth <= rr_depth:
                self.settings.russian_roulette = "off"
            else:
                warn(f"{node.where()}: pathtrace starts Russian roulette at depth 5, not {rr_depth}")

    def sensor(self, node):
        kind = node.attrs.get("type")
        cls = cameras.registry.format_class("mitsuba", kind)
        if cls is None:
            names = sorted(c.mitsuba for c in cameras.CAMERAS.values() if c.mitsuba)
            fail(node, f"pathtrace has the {', '.join(names)} sensors only")
        props = self.properties(node)
        for child in node.children:
            if child.tag == "film":
                self.film(child)
            elif child.tag == "sampler":
                self.refuse_unknown("sampler", child)
                self.settings.spp = self.declared(settings.Sampler, self.properties(child), child)["spp"]
            elif child.tag == "medium" or (child.tag == "ref" and self.resolve(child).tag == "medium"):
                self.camera_medium = self.medium(child)       # Mitsuba 3: the sensor's one medium
        m = self.get(props, "to_world", np.eye(4), ("transform",))
        given = {FILM: (self.settings.width, self.settings.height), TO_WORLD: m}
        try:
            values = parameters.read(cls.parameters + cls.format_only, "mitsuba",
                                     lambda p, name: self.parameter(props, p, name), given)
            # Mitsuba's camera space has +x to the image's left
            self.camera = cls.from_file("mitsuba", values, given, frame_of(m, x_right=False),
                                        lambda text, name=None: warn(f"{(props[name] if name else node).where()}: {text}"))
        except ValueError as e:
            refuse(props, node, e, format_names(cameras.registry.FIELDS, "mitsuba"))

    def film(self, node):
        self.refuse_unknown("film", node)
        props = self.properties(node)
        values = self.declared(settings.Film, props, node)
        self.settings.width, self.settings.height = values["width"], values["height"]
        if node.attrs.get("type") not in ("hdrfilm", "specfilm", None):
            warn(f"{node.where()}: pathtrace writes the image format of the output file's name")
        if node.attrs.get("type") != "specfilm":    # whose channels are its sensitivity functions'
            props.get("pixel_format")
        for child in node.children:
            if child.tag == "rfilter":
                self.filter = self.rfilter(child)

    def rfilter(self, node) -> filters.PixelFilter:
        """A filter by its type's declared Mitsuba names (app/filters.py); its gaussian for one of
        negative lobes."""
        props = self.properties(node)
        self.refuse_unknown("rfilter", node)
        kind = filters.format_type("mitsuba", node.attrs.get("type"), lambda text: warn(f"{node.where()}: {text}"))
        if kind is None:
            props.ignore()
            return filters.format_default("mitsuba")
        try:
            return kind.make(self.declared(kind, props, node))
        except ValueError as e:
            refuse(props, node, e, format_names(kind.parameters, "mitsuba"))

    def emitter(self, node):
        kind = node.attrs.get("type")
        props = self.properties(node)
        if self.environment is not None and kind in Environment.mitsuba_plugins:
            warn(f"{node.where()}: a second environment; pathtrace keeps the first")
            props.ignore()
            return
        if kind in Environment.mitsuba_plugins:       # by its declared Mitsuba names, those this emitter has
            values = parameters.read([p for p in Environment.parameters if p.name in Environment.mitsuba_plugins[kind]],
                                     "mitsuba", lambda p, name: self.parameter(props, p, name))
            try:
                self.environment = Environment.from_mitsuba(kind, values, lambda: self.get(
                    props, "to_world", np.eye(4), ("transform",)), node.file.parent, node.where(), warn)
            except ValueError as e:
                refuse(props, node, e)
        elif kind in LIGHTS_BY_NAME:
            self.lights.append(self.delta_light(node, kind, props))
        else:
            self.refuse_unknown("emitter", node)
            warn(f"{node.where()}: pathtrace has no {kind} emitters; it ignores this one")
            props.ignore()

    def delta_light(self, node, kind, props):
        """A delta light of pathtrace.lights by its declared Mitsuba names; a point or vector
        that the emitter places by its to_world (app/parameters.py: FRAME) is to_world's origin
        or +z, where Mitsuba's point, spot and directional emitters shine along local +z."""
        cls = LIGHTS_BY_NAME[kind]
        m = self.get(props, "to_world", np.eye(4), ("transform",))
        frame = {"point": m[:3, 3], "vector": m[:3, :3] @ [0, 0, 1.0]}
        kinds = {p.name: p.kind for p in cls.parameters}
        values = {k: frame[kinds[k]] if v is FRAME else v for k, v in self.declared(cls, props, node).items()}
        try:
            return cls.from_values(values)
        except ValueError as e:
            refuse(props, node, e)

    def declared(self, kind, props, node) -> dict:
        """The values of the parameters a type `kind` declares (app/parameters.py) that an element
        gives, converted and in range; of what it has and pathtrace has not (`unsupported`), a
        warning of each given where the kind says why."""
        for name, why in kind.unsupported.get("mitsuba", {}).items():
            if name in props and why:
                warn(f"{props[name].where()}: {why}; ignored")
        try:
            values = parameters.read(kind.parameters, "mitsuba", lambda p, name: self.parameter(props, p, name))
            error = out_of_range(kind.parameters, values)
            if error:
                raise error
        except ValueError as e:
            refuse(props, node, e, format_names(kind.parameters, "mitsuba"))
        return values

    def parameter(self, props, p, name):
        """The value of the declared parameter p (app/parameters.py) that the property `name`
        gives, by p's kind; None where the element has no such property."""
        if name not in props:
            return None
        if p.kind == "color":
            return self.color(props, name, None, textures=p.texture)
        c = props[name]
        target = self.resolve(c) if c.tag == "ref" else c
        if p.texture and target.tag == "texture":
            return self.texture(target)
        if p.texture and target.tag in ("rgb", "spectrum"):     # a constant texture, read by its luminance
            return float(np.dot(self.value(target), LUMINANCE))
        if p.kind == "image":
            return read_image(props.node.file.parent / self.get(props, name, kinds=("string",)), c.where(),
                              self.get(props, "raw", False, ("boolean",)), self.images)
        kinds = {"number": ("float",), "integer": ("integer",), "bool": ("boolean",), "string": ("string",),
                 "name": ("string",), "point": ("point", "vector"), "vector": ("vector", "point")}[p.kind]
        if p.kind == "number" and getattr(p, "names", None) and target.tag == "string":
            kinds = ("string",)          # a named value (an IOR's name), which the type resolves
        if p.texture:
            kinds += ("rgb", "texture")     # (named for the message: read above)
        return self.get(props, name, kinds=kinds)

    # -- materials --

    def material_row(self, bsdf, emission, emitter=None):
        """The material row of a shape's <bsdf> or <ref> and its area `emitter`'s radiance; shapes
        that share a BSDF and emit nothing share a row. Without a <bsdf>, Mitsuba 3 gives a shape
        a diffuse BSDF of reflectance 0.5, and an emitting one a black BSDF: a lamp then reflects
        nothing, which in the tests' scenes is 0.2 % of what the floor below it receives."""
        target = self.resolve(bsdf) if bsdf is not None and bsdf.tag == "ref" else bsdf
        key = id(target)
        if emission is None and key in self.material_rows:
            return self.material_rows[key]
        if bsdf is not None:
            material = self.material(bsdf)
        else:
            material = Material("diffuse", {"rho_d": np.full(3, 0.0 if emission is not None else 0.5)})
        if emission is not None:
            try:
                return self.builder.material(dressed(material, {"Le": emission}))
            except ValueError as e:          # a null BSDF's, which is no surface
                refuse(self.properties(emitter), emitter, e, {"Le": "radiance"})
        name = target.attrs.get("id") if target is not None else None
        self.material_rows[key] = self.builder.materials.add(material, name)
        return self.material_rows[key]

    def material(self, node) -> Material:
        """The Material of a <bsdf> (or <ref> to one)."""
        if node.tag == "ref":
            node = self.resolve(node)
            if node.tag != "bsdf":
                fail(node, "a shape's <ref> must name a <bsdf>")
        kind = node.attrs.get("type")
        props = self.properties(node)
        if kind in MITSUBA_WRAPPERS:
            return self.wrapper(node, kind, props)
        if kind == "blendbsdf":
            return self.blend(node, props)
        if kind in BSDFS_BY_NAME:
            return self.mitsuba_material(node, kind, props)
        self.refuse_unknown("bsdf", node)
        albedo = self.color(props, "base_color", None, False) if "base_color" in props else \
            self.color(props, "reflectance", 0.5, False) if "reflectance" in props else np.full(3, 0.5)
        albedo = np.clip(albedo, 0, 1)
        props.ignore()
        warn(f"{node.where()}: not supported; pathtrace uses a diffuse BSDF of albedo "
             f"{', '.join(f'{c:.3g}' for c in albedo)}")
        return Material("diffuse", {"rho_d": albedo})

    def nested_material(self, node, named=False) -> Material:
        """The Material of the BSDF a wrapper (twosided, mask, bumpmap, normalmap) holds: its
        first nested <bsdf>, whatever its name (Mitsuba 3 takes the nested objects), or <ref>
        without a name (a named one, such as a mask's opacity, can be a texture), or with one
        too where `named`."""
        inner = [c for c in node.children if c.tag == "bsdf" or c.tag == "ref" and (named or "name" not in c.attrs)]
        if not inner:
            fail(node, "needs a nested <bsdf>")
        if named and len(inner) > 2:
            fail(node, f"takes a front and a back BSDF, as Mitsuba 3's twosided does; got {len(inner)}")
        if named and len(inner) == 2:
            warn(f"{inner[1].where()}: pathtrace's two-sided materials have one BSDF on both sides; "
                 "this back BSDF is left out (the front one is used on both)")
        return self.material(inner[0])

    def blend(self, node, props) -> Material:
        """A `blendbsdf`: its two nested BSDFs, the second taken with probability `weight` (a
        number or a texture; 0.5)."""
        inner = [c for c in node.children if c.tag in ("bsdf", "ref") and c.attrs.get("name") != "weight"]
        if len(inner) != 2:
            fail(node, f"needs two nested BSDFs, got {len(inner)}")
        values = parameters.read(BSDFS["blendbsdf"].params, "mitsuba", lambda p, name: self.parameter(props, p, name))
        try:
            return blend(values.get("weight"), tuple(self.material(c) for c in inner))
        except ValueError as e:
            refuse(props, node, e)

    def wrapper(self, node, kind, props) -> Material:
        """A plugin wrapped round a nested BSDF (twosided, mask, normalmap, bumpmap): the nested
        material carrying the fields of what any material carries that the plugin gives, by their
        declared Mitsuba names (app/materials/surface.py: SURFACE), checked by `dressed`."""
        m = self.nested_material(node, named=kind == "twosided")     # Mitsuba 3's names its front and back
        fields = [p for p in SURFACE if p.mitsuba and p.mitsuba.partition(".")[0] == kind]

        def get(p, name):
            prop = name.partition(".")[2]
            if p.kind == "bool":
                return True                     # the plugin itself says it
            return self.wrapped_texture(node, props, prop) if p.kind == "texture" else self.parameter(props, p, prop)
        values = parameters.read(fields, "mitsuba", get)
        if {"normal_map", "bump_map"} & set(values) and (m.normal_map is not None or m.bump_map is not None):
            warn(f"{node.where()}: a {kind} around another map; pathtrace applies the inner one only")
            return m
        try:
            return dressed(m, values)
        except ValueError as e:
            refuse(props, node, e, {p.name: p.mitsuba.partition(".")[2] or kind for p in fields})

    def wrapped_texture(self, node, props, name) -> Texture:
        """The texture of a wrapper plugin: its nested <texture> (or <ref>) of that name, or
        (name "") its first whatever its name (a bumpmap's)."""
        maps = [c for c in node.children if c.tag == "texture" or (c.tag == "ref" and "name" in c.attrs)]
        maps = [c for c in maps if not name or c.attrs.get("name") == name]
        if not maps:
            fail(node, f'needs a <texture name="{name}">' if name else "needs a <texture>")
        if "name" in maps[0].attrs:          # the map is taken by its place, whatever its name
            props.read.add(maps[0].attrs["name"])
        target = self.resolve(maps[0]) if maps[0].tag == "ref" else maps[0]
        if target.tag != "texture":
            fail(maps[0], "must be a texture")
        return self.texture(target)

    def mitsuba_material(self, node, kind, props):
        """A material type of pathtrace's that Mitsuba 3 has, by its declared Mitsuba names
        (app/materials); Mitsuba's anisotropic roughness is alpha_u (pathtrace's alpha) and
        alpha_v, both required (its MicrofacetDistribution refuses one without the other)."""
        bsdf = BSDFS_BY_NAME[kind]
        values = parameters.read(bsdf.params, "mitsuba", lambda p, name: self.parameter(props, p, name))
        if any(p.name == "alpha_v" for p in bsdf.params) and ("alpha_v" in values or "alpha_u" in props):
            if "alpha" in props or "alpha_u" not in props or "alpha_v" not in props:
                fail(node, "give alpha, or alpha_u and alpha_v, not a mixture")
            values["alpha"] = self.parameter(props, next(p for p in bsdf.params if p.name == "alpha"), "alpha_u")
        if "distribution" in values:
            props.get("sample_visible")      # pathtrace samples visible normals always (kernels/microfacet.cl)
        try:
            error = out_of_range(bsdf.params, values)      # of what the file gave (the TOML reader's Param bounds)
            if error:
                raise error
            values = bsdf.complete(values)
        except ValueError as e:
            refuse(props, node, e, format_names(bsdf.params, "mitsuba"))
        return Material(bsdf.name, values)

    # -- media --

    def medium(self, node) -> int:
        """The row of a <medium> (or a <ref> to one) in the scene's media: Mitsuba 3's
        `homogeneous` (sigma_t and albedo, constant, times scale) with an `isotropic` or `hg`
        phase function."""
        if node.tag == "ref":
            node = self.resolve(node)
            if node.tag != "medium":
                fail(node, "a medium's <ref> must name a <medium>")
        if id(node) in self.medium_rows:
            return self.medium_rows[id(node)]
        kind = node.attrs.get("type")
        self.refuse_unknown("medium", node)
        if kind != "homogeneous":
            fail(node, f"pathtrace has homogeneous media only, not {short(kind)}")
        props = self.properties(node)
        for name in ("albedo", "sigma_t"):
            if name in props and props[name].tag == "volume":
                fail(props[name], f"{name}: pathtrace's media are homogeneous; give a float or an rgb")
        if not self.get(props, "sample_emitters", True, ("boolean",)):
            warn(f"{props['sample_emitters'].where()}: pathtrace samples emitters in every medium")
        values = self.declared(Medium, props, node)
        for phase in (c for c in node.children if c.tag == "phase"):
            phase_props = self.properties(phase)
            if phase.attrs.get("type") == "hg":
                values["g"] = self.get(phase_props, "g", 0.8, ("float",))     # Mitsuba 3's default
            elif phase.attrs.get("type") != "isotropic":
                self.refuse_unknown("phase", phase)
                phase_props.ignore()
                warn(f"{phase.where()}: pathtrace has no {phase.attrs.get('type')} phase function; "
                     "it scatters isotropically instead")
        try:
            medium = Medium.from_values(node.attrs.get("id") or f"medium {len(self.media)}", values)
        except ValueError as e:
            refuse(props, node, e)
        self.media.append(medium)
        self.medium_rows[id(node)] = len(self.media) - 1
        return self.medium_rows[id(node)]

    # -- shapes --

    def shapegroup(self, node) -> int:
        """The object of a `shapegroup` (its index in the builder), read once: its shapes in the
        group's space."""
        if id(node) not in self.groups:
            obj = self.builder.add_object(node.attrs.get("id", "shapegroup"))
            self.groups[id(node)] = obj
            for child in node.children:
                if child.tag == "shape":
                    if child.attrs.get("type") in ("shapegroup", "instance"):
                        fail(child, "a shapegroup cannot hold shapegroups or instances (nor can Mitsuba's)")
                    self.shape(child, obj)
        return self.groups[id(node)]

    def instance(self, node, props):
        """An `instance`: the shapegroup it refers to, through its to_world."""
        refs = [c for c in node.children if c.tag in ("ref", "shape")]
        target = self.resolve(refs[0]) if refs and refs[0].tag == "ref" else refs[0] if refs else None
        if target is None or target.tag != "shape" or target.attrs.get("type") != "shapegroup":
            fail(node, "needs a shapegroup (a <ref> to one)")
        self.builder.add_instance(self.shapegroup(target), self.get(props, "to_world", np.eye(4), ("transform",)),
                                  node.where())

    def shape(self, node, group: int = None):
        """A shape of the scene, or of the shapegroup whose object is `group`."""
        kind = node.attrs.get("type")
        props = self.properties(node)
        if kind == "instance":
            return self.instance(node, props)
        bsdf, emission, emitter, media = None, None, None, {}
        for child in node.children:
            # Mitsuba 3's Shape takes a BSDF by its place, whatever its name (src/render/shape.cpp,
            # the constructor's loop over props.objects()): a <ref name="bsdf"> as its exporters
            # write it, too
            if child.tag == "bsdf" or child.tag == "ref" and ("name" not in child.attrs
                                                              or self.resolve(child).tag == "bsdf"):
                bsdf = child
                if "name" in child.attrs:
                    props.read.add(child.attrs["name"])
            elif child.tag == "emitter":
                if child.attrs.get("type") != "area":
                    warn(f"{child.where()}: a shape's emitter must be area; ignored")
                    continue
                if group is not None:
                    warn(f"{child.where()}: an emitter in a shapegroup; instances have no area lights "
                         "(nor do Mitsuba's), so pathtrace ignores it")
                    continue
                emitter, emission = child, self.color(self.properties(child), "radiance", 1.0)
            elif child.tag in ("medium", "ref") and child.attrs.get("name") in ("interior", "exterior"):
                media[child.attrs["name"]] = self.medium(child)
                props.read.add(child.attrs["name"])
            elif child.tag in ("medium", "sensor"):
                warn(f"{child.where()}: not supported; ignored")
        material = self.material_row(bsdf, emission, emitter)
        # Mitsuba 3: a shape with a medium on either side is a transition, the other side vacuum
        interface = MediumInterface(media.get("interior", -1), media.get("exterior", -1)) if media else None
        m = self.get(props, "to_world", np.eye(4), ("transform",))
        name = node.attrs.get("id")
        if kind in SHAPES:
            given = {}          # the shape's Mitsuba parameters, by their names (format-only: none of pathtrace's)
            parameters.read(SHAPES[kind].mitsuba_parameters, "mitsuba", lambda p, name: self.parameter(props, p, name),
                            given)
            values, local, texture_uv, flip = SHAPES[kind].from_mitsuba(given, m, node.where())
            problem = SHAPES[kind].check(values)
            if problem:
                fail(node, f"the {kind}'s {problem}")
            shape = Shape(name or self.builder.shape_name(kind), kind, values, m @ local, material,
                          flip=flip, texture_uv=texture_uv, media=interface)
            if SHAPES[kind].too_flat(shape):
                # Mitsuba 3 would intersect it through a near-singular inverse; the kernels cannot
                # (pathtrace.shapes.shape.MIN_DETERMINANT), and what it covers is next to nothing
                warn(f"{node.where()}: to_world shrinks or flattens the {kind} beyond what the kernels can "
                     f"invert (|det| below {MIN_DETERMINANT:g}); pathtrace leaves it out")
                return
            if np.any(np.abs(np.array(shape.bounds(SHAPES[kind]))) > MAX_COORDINATE):
                fail(node, f"the {kind} reaches beyond {MAX_COORDINATE:g}, which float32 cannot trace")
            return self.builder.add_to(group, shape)
        if kind not in MESHES_BY_NAME:
            self.refuse_unknown("shape", node)
            warn(f"{node.where()}: pathtrace has no {kind} shape; it ignores this one")
            props.ignore()
            return
        k = MESHES_BY_NAME[kind]
        values = self.declared(k, props, node)
        try:
            (vertices, faces, normals, uvs), path, smoothed = k.triangles(values, MeshSource(
                lambda filename: (self.mesh_files.read(node.file.parent / filename, node.where()),
                                  str(node.file.parent / filename)),
                lambda *mesh: check_mesh(*mesh, node.where()),
                locate=lambda filename: (node.file.parent / filename, node.where())))
        except ValueError as e:
            refuse(props, node, e, format_names(k.parameters, "mitsuba"))
        flip = values.get("flip_normals", False)
        vertices, faces, normals, turned = place_mesh(vertices, faces, normals, m, flip, True, node.where())
        # a file's faces turned to its normals' side: written anew by convert
        origin = MeshFile(path, m, values.get("face_normals", False), flip, smoothed) if path and not turned else None
        self.builder.add_to(group, Mesh(name or (Path(path).stem if path else f"{kind} {len(self.builder.meshes)}"),
                                        vertices, faces, normals, material, origin.path if origin else "", origin, uvs,
                                        interface), node.where())


def read_mitsuba_file(path) -> Scene:
    return _Reader(Path(path)).read()
