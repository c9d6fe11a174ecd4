"""Where a render's tracing time goes, counted: the rays a render traces, and per ray the BVH
nodes it visits and the primitives it tests (`pathtrace bench --traversal`). The render kernels,
built with TRAVERSAL_STATS (app/device/features.py), count one of the two in place of the rays they
report (kernels/scene.cl: COUNT_WORK); as a render is deterministic for a seed, three renders of
the same samples, counting rays, nodes and primitives in turn, give the ratios. Counting costs
the kernels nothing when it is off: the counters are compiled in only with the define."""

from dataclasses import dataclass

from pathtrace.rendering.renderer import Renderer

NODES_VISITED, PRIMITIVES_TESTED = 1, 2       # kernels/scene.cl


@dataclass
class TraversalStats:
    rays_per_sample: float
    nodes_per_ray: float        # 4-wide nodes (each tests four boxes); the instances' tree's too
    primitives_per_ray: float   # sphere and triangle tests (a leaf counted whole, the triangle the ray leaves too)


def traversal_stats(backend, scene, width: int, height: int, spp: int) -> TraversalStats:
    """The counts of `spp` samples per pixel of `scene` (a Scene or CompiledScene) at its
    settings (estimator, depth), seed 0."""
    renderer = Renderer(backend, scene, width, height)
    counts = []
    for kind in (0, NODES_VISITED, PRIMITIVES_TESTED):
        renderer.count_traversal(kind)
        renderer.add_samples(spp)
        counts.append(renderer.rays_traced())
    renderer.finish()
    rays, nodes, primitives = counts
    return TraversalStats(rays / (width * height * spp), nodes / max(rays, 1), primitives / max(rays, 1))
