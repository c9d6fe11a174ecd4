"""The built-in scenes: the benchmark scenes of the report, pinned down in
../shared/bench/SCENES.md (copied into docs/benchmarks.md), and the HDR-lit demo."""

import re
from dataclasses import replace

import numpy as np

from app.camera import Camera
from app.environment import Environment
from app.resources import resource_dir
from app.scene import RenderSettings, Scene, SceneBuilder, read_scene_file


def _shipped(name: str) -> Scene:
    return read_scene_file(resource_dir("assets") / "scenes" / f"{name}.toml")


def simple() -> Scene:
    return _shipped("simple")


def simple_diffuse() -> Scene:
    """`simple` with each glossy sphere made diffuse with the same total albedo rho_d + rho_s."""
    s = simple()
    return replace(s, name="simple-diffuse", rho_d=s.rho_d + s.rho_s,
                   rho_s=np.zeros_like(s.rho_s), exponent=np.ones_like(s.exponent))


def random_spheres(n: int, diffuse_only: bool) -> Scene:
    """N spheres in the cube [-10, 10]^3, drawn in exactly the order SCENES.md gives."""
    rng = np.random.default_rng(2022)
    centres = rng.uniform(-10.0, 10.0, size=(n, 3))
    radius = 0.35 * (8000 / n) ** (1 / 3)
    albedo = rng.uniform(0.1, 0.9, size=(n, 3))
    kind = rng.uniform(0.0, 1.0, size=n)
    emitter = kind >= 0.97
    phong = (kind >= 0.7) & ~emitter & (not diffuse_only)
    b = SceneBuilder()
    b.spheres = np.column_stack([centres, np.full(n, radius)])
    b.rho_d = np.where(emitter[:, None], 0.0, np.where(phong[:, None], 0.3 * albedo, albedo))
    b.rho_s = np.where(phong[:, None], 0.6, 0.0) * np.ones((n, 3))
    b.exponent = np.where(phong, 100.0, 1.0)
    b.emission = np.where(emitter[:, None], 4.0 * albedo, 0.0)
    count = f"{n // 1000}k" if n % 1000 == 0 and n < 1_000_000 else \
        f"{n // 1_000_000}M" if n % 1_000_000 == 0 else str(n)
    return b.build(f"spheres{count}{'-diffuse' if diffuse_only else ''}",
                   camera=Camera([28, 20, 36], [0, 0, 0], [0, 1, 0], 45.0),
                   environment=Environment.constant((1, 1, 1)),
                   settings=RenderSettings(width=1920, height=1080, spp=64))


def builtin_scene(name: str):
    """A built-in scene by name, or None. Besides the named ones, 'spheresN' with N a count
    (a k or M suffix allowed, e.g. spheres512k, spheres1M) and an optional '-diffuse' gives the
    random-spheres scene of N spheres, for scaling measurements."""
    if name in BUILTIN_SCENES:
        return BUILTIN_SCENES[name]()
    m = re.fullmatch(r"spheres(\d+)([kM]?)(-diffuse)?", name)
    if m and int(m.group(1)) > 0:
        n = int(m.group(1)) * {"": 1, "k": 1000, "M": 1_000_000}[m.group(2)]
        return random_spheres(n, bool(m.group(3)))
    return None


BUILTIN_SCENES = {
    "simple": simple,
    "simple-diffuse": simple_diffuse,
    "spheres8k": lambda: random_spheres(8000, False),
    "spheres8k-diffuse": lambda: random_spheres(8000, True),
    "spheres64k": lambda: random_spheres(64000, False),
    "spheres64k-diffuse": lambda: random_spheres(64000, True),
    "demo": lambda: _shipped("demo"),
}
