"""A scene's fields checked before a render. The readers check what a file says; the Python API
lets a user change a loaded scene's fields (its settings, camera, spheres, meshes, environment),
and a value no reader would have let through must be refused in one line that names the object
and the field (`scene.settings.width`), not met as an OpenCL error, an overflow or a BVH build's
complaint."""

import math

import numpy as np

from pathtrace.cameras import Camera
from pathtrace.errors import UserError, cut, short
from pathtrace.rendering.choices import INTEGRATORS, LIGHT_SAMPLERS, MAX_PATH_QUEUE, PATH_QUEUE_AUTO, RUSSIAN_ROULETTE
from pathtrace.scene.description import Scene
from pathtrace.scene.meshes import MAX_COORDINATE

MAX_SIZE = 16384          # pixels on a side, as `--size` and the three formats allow (a film, a [render] table)
SETTING_RANGES = {"width": (1, MAX_SIZE), "height": (1, MAX_SIZE), "spp": (1, 2**31 - 1),
                  "seed": (0, 2**32 - 1), "max_depth": (0, 2**31 - 1)}
"""The integer render settings' ranges, for a scene's fields and the API's arguments alike."""


def check_scene(scene: Scene):
    """Raises UserError for the first field of `scene` out of range or of the wrong type."""
    if not isinstance(scene, Scene):
        raise UserError(f"scene: give a pathtrace.Scene or what load() takes, got {short(scene)}")
    _settings(scene.settings)
    _camera(scene.camera)
    _environment(scene.environment)
    materials = len(scene.materials)
    _spheres(scene, materials)
    for i, mesh in enumerate(scene.meshes):
        _mesh(mesh, f"scene.meshes[{i}]", materials)
    for i, shape in enumerate(scene.shapes):
        _shape(shape, f"scene.shapes[{i}]", materials)
    if scene.instances is not None:
        for k, o in enumerate(scene.instances.objects):
            for i, mesh in enumerate(o.meshes):
                _mesh(mesh, f"scene.instances.objects[{k}].meshes[{i}]", materials)


def integer(name: str, value, low: int, high: int) -> int:
    """value as an int, or a UserError naming `name` where it is not an integer in [low, high]."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise UserError(f"{name}: give an integer from {low} to {high}, got {short(value)}")
    return int(value)


def russian_roulette(name: str, value) -> str:
    """value as a Russian roulette rule, or a UserError naming `name`."""
    if not isinstance(value, str) or value not in RUSSIAN_ROULETTE:
        raise UserError(f"{name}: give one of {', '.join(RUSSIAN_ROULETTE)}, got {short(value)}")
    return value


def _settings(s):
    where = "scene.settings"
    for field, (low, high) in SETTING_RANGES.items():
        integer(f"{where}.{field}", getattr(s, field), low, high)
    russian_roulette(f"{where}.russian_roulette", s.russian_roulette)
    if not isinstance(s.nee, (bool, np.bool_)):
        raise UserError(f"{where}.nee: give True or False, got {short(s.nee)}")
    if not isinstance(s.light_sampler, str) or s.light_sampler not in LIGHT_SAMPLERS:
        raise UserError(f"{where}.light_sampler: give one of {', '.join(LIGHT_SAMPLERS)}, got {short(s.light_sampler)}")
    if not isinstance(s.integrator, str) or s.integrator not in INTEGRATORS:
        raise UserError(f"{where}.integrator: give one of {', '.join(INTEGRATORS)}, got {short(s.integrator)}")
    if not (type(s.path_queue) is int and s.path_queue == PATH_QUEUE_AUTO):
        integer(f"{where}.path_queue (or PATH_QUEUE_AUTO)", s.path_queue, 0, MAX_PATH_QUEUE)
    if not (isinstance(s.photon_radius, (int, float, np.floating)) and 0 <= s.photon_radius <= MAX_COORDINATE):
        raise UserError(f"{where}.photon_radius: give a distance in [0, {MAX_COORDINATE:g}] (0: no photons), "
                        f"got {short(s.photon_radius)}")
    if not isinstance(s.path_sort, (bool, np.bool_)):
        raise UserError(f"{where}.path_sort: give True or False, got {short(s.path_sort)}")
    if not s.paths_end:
        raise UserError(f"{where}: russian_roulette 'off' needs max_depth >= 1, or paths would never end")
    from pathtrace.filters import PixelFilter
    if not isinstance(s.filter, PixelFilter):
        raise UserError(f"{where}.filter: give a pathtrace.filters.PixelFilter (pathtrace.filters.TYPES['box'].make"
                        f"({{}}), say), got {short(s.filter)}")
    try:
        s.filter.check()
    except (ValueError, TypeError, AttributeError) as e:
        raise UserError(f"{where}.filter: {e}") from None


def _vector(name: str, value, size: int = 3, limit: float = MAX_COORDINATE) -> np.ndarray:
    try:
        v = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        v = None
    if v is None or v.shape != (size,) or not np.all(np.isfinite(v)) or not np.all(np.abs(v) <= limit):
        within = f" within {limit:g}" if limit < np.inf else ""
        raise UserError(f"{name}: give {size} finite numbers{within}, got {short(value)}")
    return v


def _number(name: str, value, low: float, high: float, open_low: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) or not math.isfinite(value) \
            or not (low < value if open_low else low <= value) or not value <= high:
        raise UserError(f"{name}: give a number in {'(' if open_low else '['}{low:g}, {high:g}], got {short(value)}")
    return float(value)


def _camera(camera):
    where = "scene.camera"
    if not isinstance(camera, Camera):
        raise UserError(f"{where}: give a pathtrace.Camera (pathtrace.cameras), got {short(camera)}")
    eye, look_at = _vector(f"{where}.eye", camera.eye), _vector(f"{where}.look_at", camera.look_at)
    up = _vector(f"{where}.up", camera.up, limit=np.inf)      # a direction: of any length
    forward = look_at - eye
    if not np.linalg.norm(forward) > 0:
        raise UserError(f"{where}.look_at: must differ from {where}.eye, got {look_at.tolist()} for both")
    if not np.linalg.norm(np.cross(forward, up)) > 1e-9 * np.linalg.norm(forward) * np.linalg.norm(up):
        raise UserError(f"{where}.up: must be neither zero nor parallel to the view direction, got {up.tolist()}")
    for p in camera.parameters:
        value = getattr(camera, p.name)
        if not p.choices and (isinstance(value, bool) or not isinstance(value, (int, float, np.number))
                            or not math.isfinite(value)):
            raise UserError(f"{where}.{p.name}: give a finite number, got {short(value)}")
    try:
        camera.check()
    except ValueError as e:
        raise UserError(f"{where}.{e}") from None


def _environment(environment):
    where = "scene.environment"
    _number(f"{where}.intensity", environment.intensity, 0.0, 1e20)
    _number(f"{where}.rotation", environment.rotation, -1e9, 1e9)
    if not np.linalg.norm(_vector(f"{where}.up", environment.up)) > 0:
        raise UserError(f"{where}.up: must not be zero")
    if not isinstance(environment.mirrored, (bool, np.bool_)):
        raise UserError(f"{where}.mirrored: give True or False, got {short(environment.mirrored)}")
    image = environment.image
    if not isinstance(image, np.ndarray) or image.ndim != 3 or image.shape[2] < 3 or 0 in image.shape \
            or not np.all(np.isfinite(image)) or np.any(image < 0):
        raise UserError(f"{where}.image: give an (H, W, 3) array of finite, non-negative radiance")


def _spheres(scene, materials: int):
    spheres, rows = scene.spheres, scene.sphere_material
    if not isinstance(spheres, np.ndarray) or spheres.ndim != 2 or spheres.shape[1] != 4:
        raise UserError(f"scene.spheres: give an (N, 4) array of centre and radius, got {short(spheres)}")
    if not isinstance(rows, np.ndarray) or rows.shape != (len(spheres),):
        raise UserError(f"scene.sphere_material: give one material row per sphere ({len(spheres)}), got {short(rows)}")
    bad = ~(np.all(np.abs(spheres[:, :3]) + spheres[:, 3:] <= MAX_COORDINATE, axis=1) & (spheres[:, 3] > 0))
    if np.any(bad):
        i = int(np.argmax(bad))
        raise UserError(f"scene.spheres[{i}]: give a finite centre within {MAX_COORDINATE:g} and a positive radius, "
                        f"got {spheres[i].tolist()}")
    _rows("scene.sphere_material", rows, materials)


def _rows(name: str, rows, materials: int):
    rows = np.asarray(rows)
    if rows.size and (not np.issubdtype(rows.dtype, np.integer) or rows.min() < 0 or rows.max() >= materials):
        bad = rows.ravel()[np.argmax((rows.ravel() < 0) | (rows.ravel() >= materials))] \
            if np.issubdtype(rows.dtype, np.integer) else rows.ravel()[0]
        raise UserError(f"{name}: material rows must be integers from 0 to {materials - 1}, got {short(bad)}")


def _mesh(mesh, where: str, materials: int):
    v, f = mesh.vertices, mesh.faces
    if not isinstance(v, np.ndarray) or v.ndim != 2 or v.shape[1] != 3 or not np.all(np.abs(v) <= MAX_COORDINATE):
        raise UserError(f"{where}.vertices: give a (V, 3) array of finite coordinates within {MAX_COORDINATE:g}")
    if not isinstance(f, np.ndarray) or f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.integer):
        raise UserError(f"{where}.faces: give an (F, 3) array of integer vertex indices, got {short(f)}")
    if f.size and (f.min() < 0 or f.max() >= len(v)):
        i = int(np.argmax(np.any((f < 0) | (f >= len(v)), axis=1)))
        raise UserError(f"{where}.faces[{i}]: refers to vertex {f[i].tolist()}, but the mesh has {len(v)} vertices")
    for name, width in (("normals", 3), ("uvs", 2)):
        a = getattr(mesh, name)
        if a is not None and (not isinstance(a, np.ndarray) or a.shape != (len(v), width)
                              or not np.all(np.isfinite(a))):
            raise UserError(f"{where}.{name}: give None or a ({len(v)}, {width}) array of finite numbers")
    integer(f"{where}.material (a row of scene.materials)", mesh.material, 0, materials - 1)


def _shape(shape, where: str, materials: int):
    from pathtrace.shapes import SHAPES, Shape
    from pathtrace.shapes.shape import flattened
    if not isinstance(shape, Shape) or shape.kind not in SHAPES:
        raise UserError(f"{where}: give a pathtrace.shapes.Shape of a kind of {', '.join(SHAPES)}, got {short(shape)}")
    params = np.asarray(shape.params, np.float64)
    if params.shape != (4,) or not np.all(np.isfinite(params)):
        raise UserError(f"{where}.params: give the {shape.kind}'s 4 finite parameters, got {short(shape.params)}")
    problem = SHAPES[shape.kind].check(tuple(params))
    if problem:
        raise UserError(f"{where}.params: {problem}")
    m = np.asarray(shape.to_world, np.float64)
    if m.shape != (4, 4) or not np.all(np.isfinite(m)) or flattened(m):
        raise UserError(f"{where}.to_world: give an invertible 4x4 affine transform, got {short(shape.to_world)}")
    integer(f"{where}.material (a row of scene.materials)", shape.material, 0, materials - 1)


MAX_NESTING = 64          # levels of dicts and lists a scene dict may hold (a TOML file's hold a few)


def check_tables(data, what: str):
    """Refuses, in one line, dicts and lists that the TOML reader could not walk: one that holds
    itself (directly or further down), nesting deeper than MAX_NESTING, or a key that is not a
    string (TOML's keys are strings). Walked with a stack of its own, so that neither a cycle nor
    5,000 levels reach Python's recursion limit."""
    todo = [(data, what, 0, ())]
    while todo:
        value, where, depth, above = todo.pop()
        where = cut(where, 100)
        if not isinstance(value, (dict, list, tuple)):
            continue
        if id(value) in above:
            raise UserError(f"{where}: holds itself (a dict or list that contains itself cannot be a scene)")
        if depth > MAX_NESTING:
            raise UserError(f"{where}: nested more than {MAX_NESTING} levels deep")
        above = above + (id(value),)
        if isinstance(value, dict):
            for key, item in value.items():
                if not isinstance(key, str):
                    raise UserError(f"{where}: keys must be strings, got {short(key)}")
                todo.append((item, f"{where}.{key}", depth + 1, above))
        else:
            todo += [(item, f"{where}[{i}]", depth + 1, above) for i, item in enumerate(value)]
