"""The compiled scene: a scene description turned into the flat, device-independent form the
kernels read (as pbrt-v4 and Mitsuba 3 do): primitives in BVH order, the BVH, the material
table, the light table and the environment's sampling tables. A Renderer per device only
uploads it. A scene's textures compile into their own tables (app/textures/table.py).
Primitives have one index space (kernels/types.h); prim_shape maps each back to the
shape of the description it came from, so that users only ever see the description's shapes."""

import os
import threading
import time
from dataclasses import dataclass

import numpy as np
import pyopencl as cl

from pathtrace.compiler.builder import expect_tree, no_device_tree
from pathtrace.compiler.bvh import BVH, column_max, column_min, primitive_boxes
from pathtrace.compiler.bvh_cache import CACHED_ONLY, NotCached, cached_bvh
from pathtrace.compiler import geometry_cache
from pathtrace.scene.environment import LUMINANCE
from pathtrace.errors import UserError, format_bytes, short
from pathtrace.device.features import FLAT_MAX, LONE_MAX, Features
from pathtrace.lights.light import MAX_RADIANCE
from pathtrace.lights import LightPlan, LightTable, build_light_table, emitted_power, light_plan, primitive_bounds
from pathtrace.materials import BSDFS, EMITS_BACK, NULL, TAGS
from pathtrace.materials.table import reachable
from pathtrace.scene.media import media_table, packed_interfaces
from pathtrace.compiler.memory import available_host_memory
from pathtrace.cameras import Camera
from pathtrace.scene.description import RenderSettings, Scene
from pathtrace.shapes import ROWS, SHAPES, Shape
from pathtrace.shapes import TAGS as SHAPE_TAGS
from pathtrace.textures import TextureTables, compile_textures
from pathtrace.scene import instances as instancing
from pathtrace.compiler.two_level import build_two_level
from pathtrace.device.types import BVH_NODE, INSTANCE, TRIANGLE


@dataclass
class ShapeRef:
    """A shape of the description, as picking reports it."""
    kind: str          # "sphere", "mesh" or "shape" (analytic)
    index: int         # into scene.spheres, the compiled scene's meshes (scene.meshes first) or scene.shapes
    name: str
    material: int      # row of scene.materials


# The scene's buffers in the order of the kernels' SCENE_KERNEL_ARGS (kernels/scene.cl)
SCENE_BUFFERS = ("nodes", "spheres", "triangles", "normals", "uvs", "prim_material", "materials", "bindings",
                 "textures", "texels", "env", "lights", "light_pick", "light_leaf", "light_nodes", "env_marginal",
                 "env_conditional", "media", "prim_media", "instances")

# The BVH build's peak host memory per primitive, measured (docs/performance.md)
BUILD_HOST_BYTES = 320


class CompiledScene:
    def __init__(self, scene: Scene, queue: cl.CommandQueue = None, progress=None, tree: bool = True):
        """queue: the device that builds the BVH (pathtrace.compiler.bvh.build_bvh, or
        pathtrace.compiler.bvh_cache reads it) and whose memory the scene must fit, or None
        (each Renderer checks its own device's, and gives build_tree its queue);
        progress(fraction) is called as the BVH build goes. tree: whether the BVH is built now.
        Without it, features() answers already (nothing it asks is changed by the tree's order)
        and build_tree() does the rest, so that a scene's program can build beside its tree
        (Renderer.set_scene): on a first start the two had run one after the other."""
        self.scene = scene
        n_spheres = len(scene.spheres)
        instances = scene.instances
        problem = instances is not None and instancing.check_instances(instances, scene.materials)
        if problem:
            raise UserError(f"{scene.source or scene.name}: {problem}")
        # a scene of few instanced triangles draws copies of them (app/scene/instances.py)
        self.two_level = instances is not None and instances.triangle_count > instancing.FLATTEN_MAX
        # the meshes whose triangles the kernels hold: the scene's (and its instances' copies),
        # then, with a two-level BVH, its objects', in their own space
        # the scene's analytic shapes (app/shapes/) are primitives of the triangle range, one each,
        # after its own meshes: the per-mesh tables below take them as meshes of one triangle
        for s in scene.shapes:
            problem = s.kind not in SHAPES and f"no shape kind {s.kind!r}" or SHAPES[s.kind].check(s.params)
            if not problem and abs(s.det) < 1e-12:
                problem = "its transform is singular"
            if problem:
                raise UserError(f"{scene.source or scene.name}: shape {short(s.name)}: {problem}")
        meshes = list(scene.meshes) + list(scene.shapes)
        if instances is not None and not self.two_level:
            meshes += instancing.flattened_meshes(instances)
        self._mesh_ends = [len(meshes)]      # where the scene's own meshes and each object's end
        if self.two_level:
            for o in instances.objects:
                meshes += o.meshes
                self._mesh_ends.append(len(meshes))
        self.meshes = meshes
        self.num_spheres = n_spheres
        self.num_triangles = sum(len(m.faces) for m in meshes)
        self.check_memory(queue.device if queue else None)
        # a few spheres beside many triangles stay out of the tree (LONE_MAX), in their order
        self.lone_spheres = n_spheres if n_spheres <= LONE_MAX and n_spheres + self.num_triangles > FLAT_MAX \
            and not self.two_level else 0
        # the materials the shapes name, which a program compiles (features)
        self.shape_materials = np.concatenate([scene.sphere_material,
                                               [m.material for m in meshes if len(m.faces)]]).astype(np.int64)
        self.light_sampler = scene.settings.light_sampler    # pathtrace.lights.LIGHT_SAMPLERS
        try:         # here, so that a problem is told before a program's build has begun beside the tree
            self.media = media_table(scene.media)
        except ValueError as e:
            raise UserError(f"{scene.source or scene.name}: {e}") from None
        self._build = (queue, progress)      # for build_tree
        self.bvh: BVH = None
        self.tree_ended = None               # when build_tree ended (perf_counter), once it has
        self._tree_lock = threading.Lock()   # a device group's renderers ask for it at once
        self._tree_tries = 0                 # builds of the tree ended, and the last one's error
        self._tree_error = None
        # a large scene compiled before takes its tree and rows from the geometry cache, and its
        # corners are not needed
        start = time.perf_counter()
        self.geometry_digest = geometry_cache.geometry_digest(scene)
        self._kept_path = geometry_cache.entry_path(self)
        self._kept = geometry_cache.read_entry(self._kept_path) if self._kept_path else None
        self._kept_seconds = time.perf_counter() - start
        # the corners as the kernels' triangle rows hold them (float4s, w filled below), gathered
        # from float32 vertices (half the bytes of float64 to move) by np.take, which is 3-4x
        # faster than NumPy's indexing with an array; whole 48-byte rows are then put in BVH
        # order by one more np.take, 3x faster than a gather into the rows' xyz
        self._corners = None if self._kept else np.concatenate(
            [np.take(float4_rows(m.vertices), m.faces, axis=0) if not isinstance(m, Shape)
             else shape_corners(m) for m in meshes]) if meshes else np.zeros((0, 3, 4), np.float32)
        self.compile_materials()
        if tree:
            self.build_tree()

    @property
    def light_plan(self) -> LightPlan:
        """What the kernels compile for the lights (light_plan): the light table's, or before the
        tree, the plan of the primitives in the scene's order, which the table will have. The
        corners are taken once: a tree built meanwhile in another thread lets them go (after
        its light table is made)."""
        corners = self._corners
        if corners is None:
            if self.tree_ended is None:      # the geometry cache holds the tree: no device needed
                self.build_tree(cached_only=True)
            return LightPlan(self.lights.types, self.lights.tree)
        counts = [len(m.faces) for m in self.meshes]
        mesh_of = np.repeat(np.arange(len(self.meshes)), counts).astype(np.int64)
        mesh_material = np.array([m.material for m in self.meshes], np.int32)
        prim_material = np.concatenate([self.scene.sphere_material, mesh_material[mesh_of]]).astype(np.int64)
        is_shape = np.array([isinstance(m, Shape) for m in self.meshes], bool)
        shape_prims = self.num_spheres + np.flatnonzero(is_shape[mesh_of])
        power, _ = self.emitted_power(self.scene.spheres, corners[:, :, :3], prim_material, shape_prims,
                                      [self.meshes[m] for m in mesh_of[shape_prims - self.num_spheres]])
        # the scene's radius, unknown before the tree's boxes, scales a light at infinity's power
        # (pi r^2 E) but not whether it emits, which is all the plan asks
        return light_plan(power, self.scene.lights, 1.0, self.light_sampler)

    def check_memory(self, device: cl.Device = None):
        """check_memory for this scene: the host's memory, and `device`'s where it is given."""
        check_memory(self.scene.name, self.num_spheres, self.num_triangles, device, self.scene.materials.texel_bytes(),
                     len(self.scene.instances) if self.two_level else 0)

    def build_tree(self, queue: cl.CommandQueue = None, cached_only: bool = False, when_bvh_built=None) -> bool:
        """The BVH, and in its order the primitives' tables, where each primitive's media are
        and the light table: what the constructor leaves to this with tree=False. queue: the
        device that builds the BVH where the cache does not hold it (default: the constructor's).
        cached_only: only where every tree it needs is had without a device (the geometry or BVH
        cache holds it, or the host builds it: pathtrace.compiler.bvh_cache.cached_bvh), so that a command
        compiles its scene while its devices open; returns whether the tree
        is built. when_bvh_built: called, where given, once the BVH is there and before the tables
        in its order are made. Once: a build that fails can be tried again. Callers in other threads wait for
        the one building it, and where it fails, raise its error rather than build it again;
        the lock goes with what the build needs (a compiled scene is pickled for the farm)."""
        lock = self._tree_lock
        if lock is None:
            return True
        tries = self._tree_tries
        with lock:
            if self.tree_ended is not None:
                return True
            if self._tree_tries != tries:        # one ended, failing, while this one waited
                raise self._tree_error
            try:
                self._build_tree(CACHED_ONLY if cached_only else queue or self._build[0], when_bvh_built)
            except NotCached:
                return False
            except BaseException as e:
                self._tree_error = e
                self._tree_tries += 1
                raise
            self._tree_tries += 1
            self._tree_error = None
            return True

    def _build_tree(self, queue, when_bvh_built=None):
        if self._kept is None:
            self._make_rows(queue, when_bvh_built)
            if self._kept_path is not None:
                geometry_cache.write_soon(self._kept_path, self)
        else:
            for name, value in self._kept.items():
                setattr(self, name, value)
            self.bvh_seconds = self._kept_seconds
            if self._build[1]:
                self._build[1](1.0)
            if when_bvh_built is not None:
                when_bvh_built()
            self.shape_prims = np.zeros(0, np.int64)
            self.instances = np.zeros(1, INSTANCE)
        self.compile_lights()
        self._corners = self._build = self._kept = None
        self.tree_ended = time.perf_counter()
        self._tree_lock = None

    def _make_rows(self, queue, when_bvh_built=None):
        """The tree, built or from the BVH cache, and the primitives' rows in its order."""
        scene, meshes, n_spheres, progress = self.scene, self.meshes, self.num_spheres, self._build[1]
        corners = self._corners
        start = time.perf_counter()
        lo, hi = primitive_boxes(scene.spheres, corners[:, :, :3])
        self.instances = np.zeros(1, INSTANCE)
        if self.two_level:
            two = build_two_level(scene, lo, hi, self._mesh_ends, meshes, queue, progress)
            self.bvh, self.instances, lo, hi = two.bvh, two.instances, two.lo, two.hi
            order = self.bvh.order
        elif self.lone_spheres:
            self.bvh = cached_bvh(lo[n_spheres:], hi[n_spheres:], 0, queue, progress)
            order = np.concatenate([np.arange(n_spheres), n_spheres + self.bvh.order])
        else:
            self.bvh = cached_bvh(lo, hi, n_spheres, queue, progress)
            order = self.bvh.order
        # the scene's bounding sphere, by which a light at infinity's power is reckoned and from
        # whose disks its light subpaths leave (kernels/lights.cl: leave_world_disk)
        self.radius = float(np.linalg.norm(column_max(hi) - column_min(lo)) / 2) if len(lo) else 1.0
        self.center = (column_max(hi) + column_min(lo)) / 2 if len(lo) else np.zeros(3)
        self.bvh_seconds = time.perf_counter() - start
        if when_bvh_built is not None:
            when_bvh_built()

        sphere_order = order[order < n_spheres]
        triangle_order = order[order >= n_spheres] - n_spheres
        self.spheres = np.ascontiguousarray(scene.spheres[sphere_order], np.float32)

        counts = [len(m.faces) for m in meshes]
        mesh_of = np.repeat(np.arange(len(meshes)), counts).astype(np.int64)
        self.triangles = take_rows(corners, triangle_order).reshape(-1, 12).view(TRIANGLE).reshape(-1)
        # per-corner shading normals and texture coordinates, in BVH order, for the triangles of
        # meshes that have them; the others' index is -1
        self.normals, normal_index = corner_table(meshes, "normals", triangle_order)
        self.triangles["v0"][:, 3] = normal_index.view(np.float32)
        self.uvs, uv_index = corner_table(meshes, "uvs", triangle_order)
        self.triangles["v1"][:, 3] = uv_index.view(np.float32)
        self.shape_prims = self.place_shapes(mesh_of[triangle_order])

        # one index space: spheres, then triangles, each in BVH order
        mesh_material = np.array([m.material for m in meshes], np.int32)
        self.prim_shape = np.concatenate([sphere_order, n_spheres + mesh_of[triangle_order]]).astype(np.int32)
        self.prim_material = np.concatenate([scene.sphere_material[sphere_order],
                                             mesh_material[mesh_of[triangle_order]] if meshes else []]).astype(np.int32)
        self.place_media(scene, sphere_order, mesh_of[triangle_order])

    def place_shapes(self, triangle_mesh: np.ndarray) -> np.ndarray:
        """Points the records of the analytic shapes (rows of the triangle range whose mesh is a
        Shape) at their rows of the side table (`normals`, appended there); returns their
        primitive indices."""
        is_shape = np.array([isinstance(m, Shape) for m in self.meshes], bool)
        rows = np.flatnonzero(is_shape[triangle_mesh]) if len(triangle_mesh) else np.zeros(0, np.int64)
        if len(rows):
            first = len(self.normals)
            self.normals = np.concatenate([self.normals] + [self.meshes[triangle_mesh[r]].rows() for r in rows])
            self.triangles["v0"][rows, 3] = (first + ROWS * np.arange(len(rows), dtype=np.int32)).view(np.float32)
        return (self.num_spheres + rows).astype(np.int64)

    def place_media(self, scene: Scene, sphere_order: np.ndarray, triangle_mesh: np.ndarray):
        """self.prim_media: per primitive, the media it bounds (one element, unread, in a scene
        without media or interfaces)."""
        spheres = scene.sphere_media
        interfaces = [m.media for m in self.meshes]
        self.media_per_primitive = bool(scene.media) or spheres is not None or any(i is not None for i in interfaces)
        if not self.media_per_primitive:
            self.prim_media = np.full(1, -1, np.int32)
        else:
            sphere_codes = packed_interfaces(spheres if spheres is not None else [None] * self.num_spheres)
            mesh_codes = packed_interfaces(interfaces)
            self.prim_media = np.concatenate([sphere_codes[sphere_order], mesh_codes[triangle_mesh]]).astype(np.int32)

    @property
    def shape_kinds(self) -> tuple:
        """The analytic shape kinds the scene has (Features.shapes)."""
        return tuple(sorted({s.kind for s in self.scene.shapes}))

    def update_materials(self):
        """Re-reads the material table, its textures and the light table (after a material edit
        or an environment change); builds the tree where it is not built, which makes the light
        table."""
        self.compile_materials()
        if self.tree_ended is None:
            self.build_tree()
        else:
            self.compile_lights()

    def compile_materials(self):
        """The material table and its textures, which the primitives' order does not change."""
        table = self.scene.materials
        # a table's entries of textures are replaced, never changed in place (MaterialTable.set)
        self.material_source = (table.rows.copy(), list(table.textures))
        # the images lights read (a goniometric light's) are textures of the same table, bound
        # after the materials' as if to materials of their own
        self._light_textures = [t for light in self.scene.lights for t in light.textures()]
        try:
            self.textures: TextureTables = compile_textures(table.textures
                                                            + [[("", 0, 3, t)] for t in self._light_textures])
        except ValueError as e:
            raise UserError(f"{self.scene.source or self.scene.name}: {e}") from None
        self.materials = table.rows.copy()
        self._material_kinds = None          # material_kinds, for this table
        self.materials["textures"] = self.textures.first[:len(table.rows)]
        check_radiance(self.scene)

    def emitted_power(self, spheres, corners, prim_material, shape_prims, shapes) -> tuple:
        """Per primitive (spheres, then triangles), the power it emits, and whether it emits
        from both sides; shape_prims: the analytic shapes' primitives, `shapes` their shapes."""
        # each material's luminance, gathered per primitive (8 bytes a primitive, not 24)
        luminance = np.take(self.materials["emission"][:, :3].astype(np.float64) @ LUMINANCE, prim_material)
        # a triangle emitting from both sides sends out twice the power of one side
        both_sides = np.take((self.materials["flags"] & EMITS_BACK) != 0, prim_material)
        both_sides[:self.num_spheres] = False
        luminance[both_sides] *= 2
        power = emitted_power(spheres, corners, luminance[:self.num_spheres], luminance[self.num_spheres:])
        power[shape_prims] = [np.pi * luminance[p] * s.world_area(SHAPES[s.kind]) for p, s in zip(shape_prims, shapes)]
        return power, both_sides

    def compile_lights(self):
        """The light table of the primitives in BVH order."""
        texture_rows = {id(t): int(self.textures.bindings["texture"][first]) for t, first
                        in zip(self._light_textures, self.textures.first[len(self.scene.materials.rows):])}
        # the corners as a view of the triangles' rows (v0, v1, v2 are consecutive float4s), not a copy
        corners = self.triangles.view(np.float32).reshape(-1, 3, 4)[:, :, :3]
        shapes = [self.meshes[int(self.prim_shape[p]) - self.num_spheres] for p in self.shape_prims]
        power, both_sides = self.emitted_power(self.spheres, corners, self.prim_material, self.shape_prims, shapes)
        self.lights: LightTable = build_light_table(power, self.scene.environment, self.scene.lights,
                                                    max(self.radius, 1e-6),
                                                    lambda prims: self.light_bounds(prims, corners, both_sides),
                                                    self.light_sampler, texture_rows)

    def light_bounds(self, prims: np.ndarray, corners: np.ndarray, both_sides: np.ndarray) -> dict:
        """The light tree's bounds of primitives `prims`: an analytic shape's normals are its
        kind's cone (app/shapes/shape.py), every direction where it emits from both sides."""
        bounds = primitive_bounds(self.spheres, corners, prims, both_sides[prims])
        # primitive_bounds' rows: the spheres of prims, then its triangles, each in prims' order
        sphere = prims < self.num_spheres
        row = np.empty(len(prims), np.int64)
        row[np.concatenate([np.flatnonzero(sphere), np.flatnonzero(~sphere)])] = np.arange(len(prims))
        for i in np.flatnonzero(np.isin(prims, self.shape_prims)):
            s = self.meshes[int(self.prim_shape[prims[i]]) - self.num_spheres]
            axis, cos = s.world_normal_cone(SHAPES[s.kind])
            bounds["axis"][row[i]] = axis
            bounds["cos_o"][row[i]] = -1.0 if both_sides[prims[i]] else cos
        return bounds

    def geometry_arrays(self) -> dict:
        """The buffers of the shapes, by their names in SCENE_BUFFERS."""
        return {"nodes": self.bvh.nodes, "spheres": self.spheres, "triangles": self.triangles,
                "normals": self.normals, "uvs": self.uvs, "prim_material": self.prim_material,
                "media": self.media, "prim_media": self.prim_media, "instances": self.instances}

    def material_arrays(self) -> dict:
        """The buffers of the materials, their textures and the light table."""
        return {"materials": self.materials, "bindings": self.textures.bindings, "textures": self.textures.textures,
                "texels": self.textures.texels, "lights": self.lights.lights, "light_pick": self.lights.pick,
                "light_leaf": self.lights.leaf,
                "light_nodes": self.lights.nodes}

    def features(self, settings: RenderSettings, camera: Camera) -> Features:
        """What the kernels need for this scene: which shapes (spheres, triangles), the material and
        light types it uses, and the Russian roulette rule, pixel filter and camera of its
        settings."""
        null_surfaces, variants, bsdfs = self.material_kinds()
        return Features(spheres=self.num_spheres > 0, triangles=self.num_triangles > 0,
                        shapes=self.shape_kinds,
                        bsdf_defines=variants, bsdfs=bsdfs,
                        textures=self.textures.types, masks=self.textures.masks,
                        normal_maps=self.textures.normal_maps, lights=self.light_plan.types,
                        light_tree=self.light_plan.tree, media=bool(self.scene.media) or null_surfaces,
                        null_surfaces=null_surfaces,
                        camera=camera.kernel, filter=settings.filter.name,
                        russian_roulette=settings.russian_roulette, instances=self.two_level,
                        lone_spheres=self.lone_spheres,
                        flat=(self.num_spheres, self.num_triangles) if self.flat else ())

    def material_kinds(self) -> tuple:
        """Whether the materials the shapes reach have null surfaces, their BSDFs' variant defines
        and their BSDFs: computed once per material table (compile_materials), as a render asks
        for its features several times (its program, its launch plan), and a table of a million
        materials (spheres1M) took 0.5 s each time."""
        if self._material_kinds is None:
            found = reachable(self.materials, self.shape_materials)
            rows = self.materials if len(found) == len(self.materials) else self.materials[found]
            used = np.unique(rows["type"])
            null_surfaces = bool(np.any(rows["flags"] & NULL))     # rays cross them (NULL_SURFACES)
            variants = tuple(sorted({d for name, tag in TAGS.items() if tag in used
                                     for d in BSDFS[name].defines(rows[rows["type"] == tag])}))
            self._material_kinds = null_surfaces, variants, tuple(name for name, tag in TAGS.items() if tag in used)
        return self._material_kinds

    @property
    def flat(self) -> bool:
        """Whether rays test every primitive, with no tree (app/device/features.py: FLAT_MAX)."""
        return self.num_spheres + self.num_triangles <= FLAT_MAX and not self.two_level

    @property
    def layout(self) -> int:
        """The LAYOUT_* bits (kernels/scene.cl) by which a generic program reads this scene's
        buffers."""
        return ((LAYOUT_LONE_SPHERES if self.lone_spheres else 0) | (LAYOUT_INSTANCES if self.two_level else 0)
                | (LAYOUT_MEDIA if self.media_per_primitive else 0) | (LAYOUT_LIGHT_TREE if self.lights.tree else 0)
                | (LAYOUT_FLAT | self.num_triangles << LAYOUT_FLAT_TRIANGLES if self.flat else 0)
                | (LAYOUT_MASKS if self.textures.masks else 0) | (LAYOUT_SHAPES if self.shape_kinds else 0))

    def shape(self, prim: int) -> ShapeRef:
        """The description's shape that primitive `prim` (BVH order) belongs to."""
        shape = int(self.prim_shape[prim])
        if shape < self.num_spheres:
            return ShapeRef("sphere", shape, self.scene.sphere_name(shape),
                            int(self.scene.sphere_material[shape]))
        mesh = self.meshes[shape - self.num_spheres]
        if isinstance(mesh, Shape):
            return ShapeRef("shape", list(self.scene.shapes).index(mesh), mesh.name, mesh.material)
        return ShapeRef("mesh", shape - self.num_spheres, mesh.name, mesh.material)


# kernels/scene.cl
LAYOUT_LONE_SPHERES, LAYOUT_INSTANCES, LAYOUT_MEDIA, LAYOUT_LIGHT_TREE, LAYOUT_FLAT = 1, 2, 4, 8, 16
LAYOUT_FLAT_TRIANGLES = 8
LAYOUT_MASKS, LAYOUT_SHAPES = 32, 64


def float4_rows(rows) -> np.ndarray:
    """(N, 3) rows (vertices, normals) as the kernels' float4s: (N, 4) float32, w 0."""
    out = np.zeros((len(rows), 4), np.float32)
    out[:, :3] = rows
    return out


GATHER_SPLIT = 1 << 18       # rows from which take_rows gathers in parts


def take_rows(values: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """np.take(values, indices, axis=0) for valid indices, in parts on up to eight of the host's
    cores where it is large: a gather of a large scene's rows in BVH order waits on memory, and
    np.take releases the GIL, so threads overlap the waits. Threads of its own, not a pool's: a
    pool made at import outlives neither a fork nor the interpreter's shutdown."""
    n, parts = len(indices), min(os.cpu_count() or 1, 8)
    if n < GATHER_SPLIT or parts == 1:
        return np.take(values, indices, axis=0)
    out = np.empty((n,) + values.shape[1:], values.dtype)
    ends = np.linspace(0, n, parts + 1).astype(np.int64)
    # mode "clip": with "raise", np.take gathers into a buffer of its own and copies it to `out`
    threads = [threading.Thread(target=np.take, args=(values, indices[a:b], 0, out[a:b], "clip"))
               for a, b in zip(ends, ends[1:])]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return out


def shape_corners(shape: Shape) -> np.ndarray:
    """An analytic shape's record in the triangle range, (1, 3, 4): its world box's corners in
    the corners' places (lower, upper, lower), so that the BVH and the light tree see its box as
    a triangle's; its kind's tag in v2.w (kernels/shapes/analytic.cl), its side-table row in v0.w
    (CompiledScene.place_shapes) and -1 in v1.w (no uv table)."""
    lo, hi = shape.bounds(SHAPES[shape.kind])
    out = np.zeros((1, 3, 4), np.float32)
    out[0, :, :3] = [lo, hi, lo]
    out[0, 1, 3] = np.int32(-1).view(np.float32)
    out[0, 2, 3] = np.int32(SHAPE_TAGS[shape.kind]).view(np.float32)
    return out


def corner_table(meshes: list, attribute: str, triangle_order: np.ndarray) -> tuple:
    """The per-vertex `attribute` ("normals" or "uvs") of the meshes that have it, gathered per
    triangle corner in BVH order (at least one row, as buffers cannot be empty): normals as the
    kernels' float4s (float4_rows), uvs as float2s; and each triangle's index of its first corner
    there, or -1 for a triangle of a mesh without it."""
    width = 4 if attribute == "normals" else 2
    having = [m for m in meshes if getattr(m, attribute) is not None]
    if not having:
        return np.zeros((1, width), np.float32), np.full(len(triangle_order), -1, np.int32)
    # the meshes' values end to end (normals padded to float4s there, where there is one row per
    # vertex, not three per triangle: a pass over the corners fewer, 0.1 s of 850 meshes' 0.87M
    # triangles on two cores), their faces indexing them, and each triangle's rank among the
    # triangles that have values: one gather in BVH order, no per-triangle copy before it
    values = np.concatenate([getattr(m, attribute) for m in having]).astype(np.float32)
    if width == 4:
        values = float4_rows(values)
    starts = np.cumsum([0] + [len(getattr(m, attribute)) for m in having[:-1]])
    faces = np.concatenate([m.faces + start for m, start in zip(having, starts)])
    has = np.concatenate([np.full(len(m.faces), getattr(m, attribute) is not None) for m in meshes])
    rank = np.cumsum(has) - 1
    with_it = has[triangle_order]
    table = take_rows(values, take_rows(faces, rank[triangle_order[with_it]]).reshape(-1)).reshape(-1, width)
    index = np.full(len(triangle_order), -1, np.int32)
    index[with_it] = np.arange(np.count_nonzero(with_it), dtype=np.int32) * 3
    return (table if len(table) else np.zeros((1, width), np.float32)), index


def check_radiance(scene: Scene):
    """Refuses, in one line, radiance beyond MAX_RADIANCE (or not finite)."""
    emission = scene.materials.rows["emission"][:, :3].astype(np.float64)
    env = scene.environment
    brightest_env = float(np.max(env.image)) * float(env.intensity)
    where = scene.source or scene.name
    # in float32, as the readers' bounds compare (pathtrace.parameters.out_of_range): 1e20 given
    # is 1.00000002e20 in the rows and the map
    if emission.size and not np.max(emission) <= np.float32(MAX_RADIANCE):
        row = int(np.argmax(np.max(np.nan_to_num(emission, nan=np.inf), axis=1)))
        name = scene.materials.name_of(row) or f"#{row}"
        value = np.max(emission[row])
        problem = (f"an emitted radiance of {value:.3g} is beyond {MAX_RADIANCE:g}, where the sums of samples overflow"
                   if not np.isnan(value) else "an emitted radiance that is not a number (NaN)")
        raise UserError(f"{where}: material {short(name)}: {problem}")
    if not brightest_env <= np.float32(MAX_RADIANCE):
        source = "" if env.source == "constant" else f" (map {short(env.source)})"
        raise UserError(f"{where}: the environment's radiance times its intensity reaches {brightest_env:.3g}{source}, "
                        f"beyond {MAX_RADIANCE:g}, where the sums of samples overflow")


def compile_scene(scene: Scene, queue: cl.CommandQueue = None, progress=None, tree: bool = True) -> CompiledScene:
    return CompiledScene(scene, queue, progress, tree)


def compile_before_devices(scene: Scene, progress=None) -> CompiledScene:
    """The scene compiled with no device, so that it runs while the devices open (api.prepare,
    the viewer): its tree too where the BVH cache holds it or the host builds it (no_device_tree),
    else the first renderer builds the tree on its device, beside its program's build
    (Renderer.set_scene; expect_tree)."""
    compiled = CompiledScene(scene, None, progress, tree=False)
    if compiled.build_tree(cached_only=True):
        no_device_tree()
    else:
        expect_tree()
    return compiled


def check_memory(name: str, n_spheres: int, n_triangles: int, device: cl.Device = None, texel_bytes: int = 0,
                 n_instances: int = 0):
    """Refuses, with one line and before anything is allocated, a scene whose BVH build would not
    fit in the host's available memory, or whose buffers would not fit on `device`."""
    from pathtrace.device.opencl import check_fits

    n = n_spheres + n_triangles + n_instances
    available = available_host_memory()
    if available is not None and n * BUILD_HOST_BYTES + texel_bytes > available:
        raise UserError(f"{name}: building the BVH of {n} primitives needs about "
                        f"{format_bytes(n * BUILD_HOST_BYTES)} of memory; {format_bytes(available)} is available")
    if device is not None:   # the largest each buffer can be (Renderer.set_scene uploads them)
        check_fits(device, {"BVH": BVH_NODE.itemsize * max(2 * n // 3, 1), "spheres": 16 * n_spheres,
                            "triangles": TRIANGLE.itemsize * n_triangles,
                            "shading normals": 3 * 16 * n_triangles, "texture coordinates": 3 * 8 * n_triangles,
                            "materials": 4 * n, "textures": texel_bytes,
                            "instances": INSTANCE.itemsize * n_instances}, name)
