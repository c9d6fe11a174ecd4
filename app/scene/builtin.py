"""The built-in scenes: the benchmark scenes of the report this project grew from (pinned down in
docs/benchmarks.md), the HDR-lit demo, the Utah teapot and a Cornell box. The shipped ones are
TOML files in assets/scenes; the random-sphere scenes are generated."""

import re

import numpy as np

from pathtrace.cameras import PerspectiveCamera
from pathtrace.scene.environment import Environment
from pathtrace.materials import pack
from pathtrace.resources import resource_dir
from pathtrace.scene.description import RenderSettings, Scene, SceneBuilder
from pathtrace.scene.toml_reader import read_scene_file


def _shipped(name: str) -> Scene:
    return read_scene_file(resource_dir("assets") / "scenes" / f"{name}.toml")


def simple_diffuse() -> Scene:
    """`simple` with each glossy sphere made diffuse with the same total albedo rho_d + rho_s."""
    s = _shipped("simple")
    rows = s.materials.rows
    for i in range(len(rows)):
        m = s.materials.get(i)
        if m.type == "phong":
            rows[i] = pack("diffuse", {"rho_d": m.params["rho_d"] + m.params["rho_s"]}, m.emission)[0]
    s.name = "simple-diffuse"
    return s


def material_spheres_hdr() -> Scene:
    """`material-spheres` under the shipped HDR map instead of its constant sky."""
    s = _shipped("material-spheres")
    s.environment = Environment.from_file(resource_dir("assets") / "envmaps" / "studio_small_03_1k.hdr")
    s.name = "material-spheres-hdr"
    return s


def random_spheres(n: int, diffuse_only: bool) -> Scene:
    """N spheres in the cube [-10, 10]^3, drawn in exactly the order docs/benchmarks.md gives."""
    rng = np.random.default_rng(2022)
    centres = rng.uniform(-10.0, 10.0, size=(n, 3))
    radius = 0.35 * (8000 / n) ** (1 / 3)
    albedo = rng.uniform(0.1, 0.9, size=(n, 3))
    kind = rng.uniform(0.0, 1.0, size=n)
    emitter = kind >= 0.97
    phong = (kind >= 0.7) & ~emitter & (not diffuse_only)
    diffuse = ~emitter & ~phong
    b = SceneBuilder()
    material = np.zeros(n, np.int32)
    material[diffuse] = b.materials.add_rows(pack("diffuse", {"rho_d": albedo[diffuse]}))
    material[phong] = b.materials.add_rows(pack("phong", {"rho_d": 0.3 * albedo[phong], "rho_s": 0.6, "n": 100.0}))
    material[emitter] = b.materials.add_rows(pack("black", {}, emission=4.0 * albedo[emitter]))
    return Scene(f"spheres{count_name(n)}{'-diffuse' if diffuse_only else ''}",
                 np.column_stack([centres, np.full(n, radius)]).astype(np.float32), material,
                 b.materials, camera=PerspectiveCamera([28, 20, 36], [0, 0, 0], [0, 1, 0], 45.0),
                 environment=Environment.constant((1, 1, 1)),
                 settings=RenderSettings(width=1920, height=1080, spp=64))


def height_field(triangles: int) -> Scene:
    """A bumpy height field of about `triangles` triangles with a sphere on it, under a sky: the
    scaling scene for meshes (the same field as Mitsuba's side-by-side timing of a 1M-triangle
    mesh)."""
    from pathtrace.scene.description import Mesh, diffuse
    v, f = height_field_mesh(triangles)
    builder = SceneBuilder()
    builder.add_mesh(Mesh("height field", v, f, None, builder.material(diffuse(0.6))))
    builder.add_sphere((0.3, 0.35, 0.2), 0.25, diffuse((0.8, 0.3, 0.2)), "ball")
    return builder.build(f"heightfield{count_name(triangles)}", camera=PerspectiveCamera([0, 1.6, 2.4], [0, 0, 0], [0, 1, 0], 45.0),
                         environment=Environment.constant((0.8, 0.85, 1.0)),
                         settings=RenderSettings(width=1920, height=1080, spp=64))


def height_field_mesh(triangles: int):
    """The vertices (float32) and triangles (int32, counter-clockwise seen from +y) of a bumpy
    height field over [-1, 1]^2 of about `triangles` triangles."""
    n = max(int(np.sqrt(triangles / 2)), 1)
    x, z = np.meshgrid(np.linspace(-1, 1, n + 1), np.linspace(-1, 1, n + 1))
    y = 0.08 * np.sin(9 * x) * np.cos(7 * z)
    v = np.stack([x, y, z], -1).reshape(-1, 3).astype(np.float32)
    i = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
    a, b, c, d = i, i + 1, i + n + 1, i + n + 2
    f = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])
    return v, f.astype(np.int32)


def count_name(n: int) -> str:
    return f"{n // 1000}k" if n % 1000 == 0 and n < 1_000_000 else \
        f"{n // 1_000_000}M" if n % 1_000_000 == 0 else str(n)


def builtin_maker(name: str):
    """What makes the built-in scene `name`, without making it, or None. Besides the named ones,
    'spheresN' with N a count (a k or M suffix allowed, e.g. spheres512k, spheres1M) and an
    optional '-diffuse' gives the random-spheres scene of N spheres, and 'heightfieldN' a height
    field of about N triangles, for scaling measurements."""
    if name in BUILTIN_SCENES:
        return BUILTIN_SCENES[name]
    m = re.fullmatch(r"(spheres|heightfield)(\d+)([kM]?)(-diffuse)?", name)
    if not m or (m.group(1) == "heightfield" and m.group(4)):
        return None
    n = int(m.group(2)) * {"": 1, "k": 1000, "M": 1_000_000}[m.group(3)]
    if not 0 < n <= MAX_GENERATED:
        return None
    spheres = m.group(1) == "spheres"

    def make():
        _check_generation(name, n, "spheres" if spheres else "triangles",
                          *(MAKE_SPHERE_BYTES if spheres else MAKE_TRIANGLE_BYTES))
        return random_spheres(n, bool(m.group(4))) if spheres else height_field(n)
    return make


MAX_GENERATED = 100_000_000    # spheres or triangles of a generated scene (the k or M suffix applied)
# The host memory per primitive of making a generated scene: at its peak, and what the scene
# keeps through its BVH build (tracemalloc, 2026-12-03: a sphere 450 and 287 bytes, its own
# material row each; a triangle 82 and 18)
MAKE_SPHERE_BYTES, MAKE_TRIANGLE_BYTES = (460, 290), (90, 20)


def _check_generation(name: str, n: int, what: str, peak: int, kept: int):
    """Refuses, in one line and before anything is allocated, a generated scene that could not be
    made, or kept while its BVH is built, in the host's available memory
    (app/compiler/compiled.py: check_memory checks the build alone, once the scene is made)."""
    from pathtrace.compiler.compiled import BUILD_HOST_BYTES
    from pathtrace.compiler.memory import available_host_memory
    from pathtrace.errors import UserError, format_bytes
    available, needed = available_host_memory(), n * max(peak, kept + BUILD_HOST_BYTES)
    if available is not None and needed > available:
        raise UserError(f"{name}: making {n:,} {what} and building their BVH needs about {format_bytes(needed)} of "
                        f"memory; {format_bytes(available)} is available")


BUILTIN_SCENES = {
    "simple": lambda: _shipped("simple"),
    "simple-diffuse": simple_diffuse,
    "spheres8k": lambda: random_spheres(8000, False),
    "spheres8k-diffuse": lambda: random_spheres(8000, True),
    "spheres64k": lambda: random_spheres(64000, False),
    "spheres64k-diffuse": lambda: random_spheres(64000, True),
    "demo": lambda: _shipped("demo"),
    "teapot": lambda: _shipped("teapot"),
    "teapot-sky": lambda: _shipped("teapot-sky"),
    "teapot-textured": lambda: _shipped("teapot-textured"),
    "cornell-box": lambda: _shipped("cornell-box"),
    "materials": lambda: _shipped("materials"),
    "material-spheres": lambda: _shipped("material-spheres"),
    "material-spheres-hdr": material_spheres_hdr,
}
