"""A scene as its file states it, in file order: spheres and triangle meshes with materials, an
environment, a camera and render settings. app/compiler/compiled.py turns it into the flat,
device-independent form the kernels read."""

from dataclasses import dataclass, field, replace

import numpy as np

from pathtrace.cameras import Camera, PerspectiveCamera
from pathtrace.scene.environment import Environment
from pathtrace.errors import UserError, warn
from pathtrace.filters import PixelFilter
from pathtrace.materials import NULL, TRANSMISSIVE, Material, MaterialTable
from pathtrace.scene.media import MediumInterface
from pathtrace.scene.named import NamedList, name_and_index, vector
from pathtrace.scene.meshes import is_closed


@dataclass
class RenderSettings:
    width: int = 960
    height: int = 540
    spp: int = 64
    max_depth: int = 0            # 0: paths end by Russian roulette alone
    russian_roulette: str = "throughput"   # one of pathtrace.rendering.choices.RUSSIAN_ROULETTE
    seed: int = 0
    nee: bool = True              # next-event estimation with MIS; off: the report's estimator
    filter: PixelFilter = field(default_factory=PixelFilter)   # where samples land in a pixel
    light_sampler: str = "auto"   # how NEE chooses a light: one of pathtrace.rendering.choices.LIGHT_SAMPLERS
    path_queue: int = 0           # paths going on past this many vertices are traced on from a queue
                                  # (kernels/integrator.cl, PATH_QUEUE): the same image, sooner on
                                  # GPUs where few paths go on long; 0: no queue;
                                  # PATH_QUEUE_AUTO (pathtrace.rendering.choices): chosen by trial renders on GPUs
    path_sort: bool = False       # the queue's paths traced on in the order of the ray each
                                  # traces next (kernels/path_sort.cl, PATH_SORT): the same image;
                                  # only where launches use the queue
    integrator: str = "path"      # one of pathtrace.rendering.choices.INTEGRATORS
    photon_radius: float = 0.0    # with bdpt: caustic photons (kernels/photons.cl) gathered within
                                  # this radius at the first pass, shrinking after; 0: none

    def __setattr__(self, name, value):
        # a misspelt setting (settings.sppp = 4) would change nothing: say so, as a camera does
        if name not in self.__dataclass_fields__:
            raise AttributeError(f"render settings have no {name!r} (they have: {', '.join(self.__dataclass_fields__)})")
        super().__setattr__(name, value)

    @property
    def paths_end(self) -> bool:
        """Whether these settings end every path: without Russian roulette only max_depth
        does. The scene files, the command line and the viewer's panel all refuse the others."""
        return self.russian_roulette != "off" or self.max_depth > 0


@dataclass
class MeshFile:
    """Where a mesh read from a file came from, so that a converted scene refers to the file."""
    path: str
    matrix: np.ndarray            # the 4x4 transform applied to the file's vertices
    face_normals: bool = False    # the file's vertex normals were dropped
    flip_normals: bool = False    # the front side was turned round
    smooth: bool = False          # normals were computed where the file has none


@dataclass
class Mesh:
    """A triangle mesh in world space (its transform applied)."""
    name: str
    vertices: np.ndarray          # (V, 3) float32
    faces: np.ndarray             # (F, 3) int32, counter-clockwise seen from the front
    normals: np.ndarray | None    # (V, 3) float32 shading normals, or None (flat shading)
    material: int                 # row of the scene's MaterialTable
    source: str = ""              # the file it came from, if any
    file: MeshFile | None = None  # and how it was read
    uvs: np.ndarray | None = None # (V, 2) float32 texture coordinates, v = 0 at an image's top
                                  # row (Mitsuba 3's convention), or None: (0, 0)
    media: MediumInterface | None = None   # the media it bounds, or None: it changes no medium

    def __post_init__(self):
        # the kernels' types, whatever a reader computed them in
        self.vertices, self.faces = np.asarray(self.vertices, np.float32), np.asarray(self.faces, np.int32)
        self.normals = None if self.normals is None else np.asarray(self.normals, np.float32)
        self.uvs = None if self.uvs is None else np.asarray(self.uvs, np.float32)

    def __repr__(self) -> str:
        return (f"<Mesh {self.name!r}: {len(self.vertices)} vertices, {len(self.faces)} triangles, material "
                f"{self.material}{', smooth normals' if self.normals is not None else ''}"
                f"{', uvs' if self.uvs is not None else ''}{f', from {self.source}' if self.source else ''}>")


@dataclass
class Scene:
    name: str
    spheres: np.ndarray           # (N, 4) float32: centre, radius
    sphere_material: np.ndarray   # (N,) int32: row of `materials`
    materials: MaterialTable
    meshes: list = field(default_factory=list)
    sphere_names: list = None     # None: "sphere i"
    camera: Camera = field(default_factory=PerspectiveCamera)
    environment: Environment = field(default_factory=lambda: Environment.constant((1, 1, 1)))
    settings: RenderSettings = field(default_factory=RenderSettings)
    source: str = ""              # the file it was read from (for messages), if any
    lights: list = field(default_factory=list)   # its delta lights (pathtrace.lights: point, spot,
                                                 # directional); emissive shapes are its area lights
    media: list = field(default_factory=list)    # its participating media (pathtrace.scene.media.Medium)
    sphere_media: list = None     # per sphere, the MediumInterface it bounds or None; None: none does
    camera_medium: int = -1       # the medium the camera is in (a row of `media`), or -1: none
    instances: object = None      # pathtrace.scene.instances.Instances: meshes drawn many times,
                                  # or None. Their meshes are not among `meshes`
    shapes: list = field(default_factory=list)   # its analytic shapes (pathtrace.shapes.Shape)

    def __post_init__(self):
        # lists that also answer by name (pathtrace.scene.named), for notebooks; kept as they are
        # where they already are, so that with_settings shares them
        if not isinstance(self.meshes, NamedList):
            self.meshes = NamedList(self.meshes, kind=("mesh", "meshes"))
        if not isinstance(self.lights, NamedList):
            self.lights = NamedList(self.lights, name_and_index, ("light", "lights"))
        if not isinstance(self.shapes, NamedList):
            self.shapes = NamedList(self.shapes, kind=("shape", "shapes"))

    def __repr__(self) -> str:
        """One line: what it holds, where it is, the camera and the image it renders; never its
        arrays."""
        s, c = self.settings, self.camera

        def count(n, word, plural=None):
            return f"{n} {word if n == 1 else plural or word + 's'}"
        parts = [count(len(self.spheres), "sphere"),
                 f"{count(len(self.meshes), 'mesh', 'meshes')} ({count(self.triangle_count, 'triangle')})"]
        if len(self.shapes):
            parts.append(count(len(self.shapes), "analytic shape"))
        if self.instances is not None and len(self.instances):
            instances = self.instances
            parts.append(f"{count(len(instances), 'instance')} ({count(instances.triangle_count, 'triangle')})")
        parts += [count(len(self.materials), "material"), count(len(self.lights), "delta light")]
        if self.media:
            parts.append(f"{len(self.media)} media")
        bounds = self.bounds()
        where = f"bounds {vector(bounds[0])} to {vector(bounds[1])}" if bounds is not None else "empty"
        return (f"<Scene {self.name!r}: {', '.join(parts)}; {where}; camera at {vector(c.eye)} looking at "
                f"{vector(c.look_at)}; {s.width}x{s.height}, {s.spp} spp"
                f"{f'; from {self.source}' if self.source else ''}>")

    def bounds(self):
        """(lower, upper) corners of the box round its spheres, meshes, analytic shapes and
        instances (world space; an instance's as its object's box moved there, which may be
        larger than its triangles'), or None where it has none."""
        lows, highs = [], []
        if len(self.spheres):
            centre, radius = self.spheres[:, :3], self.spheres[:, 3:4]
            lows.append((centre - radius).min(0))
            highs.append((centre + radius).max(0))
        for m in self.meshes:
            if len(m.vertices):
                lows.append(m.vertices.min(0))
                highs.append(m.vertices.max(0))
        if len(self.shapes):
            from pathtrace.shapes import SHAPES
            for s in self.shapes:
                lo, hi = s.bounds(SHAPES[s.kind])
                lows.append(lo)
                highs.append(hi)
        if self.instances is not None and len(self.instances):
            from pathtrace.scene.instances import world_boxes
            lo, hi = world_boxes(self.instances)
            placed = np.all(lo <= hi, axis=1)           # not the empty objects' instances
            if placed.any():
                lows.append(lo[placed].min(0))
                highs.append(hi[placed].max(0))
        return (np.min(lows, 0), np.max(highs, 0)) if lows else None

    @property
    def textures(self) -> dict:
        """The textures its materials use (their inputs included), by name ("texture N" where a
        texture has none): to look at; change a material's to change a texture."""
        found = self.materials.all_textures()
        return {t.name or f"texture {i}": t for i, t in enumerate(found)}

    def with_settings(self, **changes) -> "Scene":
        return replace(self, settings=replace(self.settings, **changes))

    def sphere_name(self, i: int) -> str:
        return self.sphere_names[i] if self.sphere_names else f"sphere {i}"

    @property
    def triangle_count(self) -> int:
        """The triangles of `meshes` (instances' not counted)."""
        return sum(len(m.faces) for m in self.meshes)


class SceneBuilder:
    """Collects shapes and materials; the built-in scenes and the file readers use it."""

    def __init__(self):
        self.materials = MaterialTable()
        self.spheres, self.sphere_material, self.sphere_names, self.meshes = [], [], [], []
        self.sphere_media = []
        self.shapes = []
        self.objects, self.instance_object, self.instance_to_world = [], [], []
        self.shapes_named = {}       # analytic shapes named so far, by kind (shape_name)

    def shape_name(self, kind: str) -> str:
        """A name for a reader's unnamed analytic shape of `kind`: "sphere 0", "sphere 1", ...,
        numbered by kind whatever range it lands in (a whole sphere goes to the sphere range)."""
        count = self.shapes_named.get(kind, 0)
        self.shapes_named[kind] = count + 1
        return f"{kind} {count}"

    def material(self, material) -> int:
        """A row for a Material (added) or an existing row index."""
        return material if isinstance(material, (int, np.integer)) else self.materials.add(material)

    def add_sphere(self, center, radius, material, name=None, media: MediumInterface = None):
        self.spheres.append((*center, radius))
        self.sphere_media.append(media)
        self.sphere_material.append(self.material(material))
        self.sphere_names.append(name or f"sphere {len(self.spheres) - 1}")

    def add_mesh(self, mesh: Mesh, where: str = None):
        """Adds a mesh; one that rays cross (a null or transmissive material) into a medium but
        has no inside (an open mesh) is warned of, at `where` (the file and line that give it):
        rays that pass its edges never enter or leave the medium."""
        crossed = self.materials.rows[mesh.material]["flags"] & (NULL | TRANSMISSIVE)
        if mesh.media is not None and crossed and len(mesh.faces) and not is_closed(mesh.vertices, mesh.faces):
            warn(f"{where + ': ' if where else ''}mesh {mesh.name!r}{f' ({mesh.source})' if mesh.source else ''}: bounds a medium but is not "
                 "closed; rays that miss it never enter or leave the medium")
        self.meshes.append(mesh)

    def add_shape(self, shape, keep_kind=False):
        """Adds an analytic shape (pathtrace.shapes.Shape), as a sphere of the sphere range where
        one renders it alike (ShapeKind.fast_range) unless `keep_kind` (the kinds' own tests)."""
        from pathtrace.shapes import SHAPES
        fast = None if keep_kind else SHAPES[shape.kind].fast_range(shape, self.materials.reads_frame(shape.material))
        if fast is not None:
            self.add_sphere(*fast, shape.material, shape.name, shape.media)
        else:
            self.shapes.append(shape)

    def add_to(self, group: int | None, item, where: str = None):
        """Adds a Mesh or an analytic Shape to the object `group` (add_object's index), or to the
        scene where it is None; `where`: as for add_mesh."""
        if group is not None:
            (self.objects[group].meshes if isinstance(item, Mesh) else self.objects[group].shapes).append(item)
        else:
            self.add_mesh(item, where) if isinstance(item, Mesh) else self.add_shape(item)

    def add_object(self, name: str) -> int:
        """A new, empty object (SceneObject) that instances may draw; its index."""
        from pathtrace.scene.instances import SceneObject
        self.objects.append(SceneObject(name))
        return len(self.objects) - 1

    def add_instance(self, obj: int, to_world: np.ndarray, where: str = None):
        """An instance of object `obj` through the 4x4 world-from-object transform: its meshes
        drawn through it (Scene.instances), its analytic shapes copied into the world (an analytic
        shape takes any affine transform: a sphere under one that stretches unevenly is the
        ellipsoid pbrt-v4 intersects). A reader gives `where` (its file and line), which an error
        names; the API's instances are checked at render (instances.check_instances)."""
        from pathtrace.scene.instances import MIN_DETERMINANT, determinant, near_singular
        m = np.asarray(to_world, np.float64)
        o = self.objects[obj]
        if where is not None and o.meshes and near_singular(m):
            raise UserError(f"{where}: the instance's transform is too near singular for pathtrace's instances "
                            f"(the determinant of its 3x3 part is {determinant(m):.3g}; they need "
                            f"at least {MIN_DETERMINANT:g} in magnitude)")
        if o.meshes:
            self.instance_object.append(obj)
            self.instance_to_world.append(m)
        for s in o.shapes:
            self.add_shape(replace(s, to_world=m @ np.asarray(s.to_world, np.float64)))

    def build(self, name, **kwargs) -> Scene:
        if not (self.spheres or self.meshes or self.shapes or self.instance_object):
            # Mitsuba 3 and pbrt-v4 render such a file: its environment alone (an HDR map looked
            # at), or black
            warn(f"{kwargs.get('source') or name}: the scene has no shapes; pathtrace renders its environment alone")
        if self.instance_object:
            from pathtrace.scene.instances import Instances
            kwargs["instances"] = Instances(self.objects, np.asarray(self.instance_object, np.int32),
                                            np.asarray(self.instance_to_world, np.float64).reshape(-1, 4, 4))
        return Scene(name, np.asarray(self.spheres, np.float32).reshape(-1, 4),
                     np.asarray(self.sphere_material, np.int32).reshape(-1), self.materials,
                     self.meshes, self.sphere_names or None,
                     sphere_media=self.sphere_media if any(m is not None for m in self.sphere_media) else None,
                     shapes=self.shapes, **kwargs)


def diffuse(rho_d) -> Material:
    return Material("diffuse", {"rho_d": rho_d})


def phong(rho_d, rho_s, n) -> Material:
    return Material("phong", {"rho_d": rho_d, "rho_s": rho_s, "n": n})


def emitter(le) -> Material:
    return Material("black", emission=np.broadcast_to(np.asarray(le, np.float64), 3).copy())
