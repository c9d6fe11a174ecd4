"""app/bench/traversal_stats.py: the counts of the BVH's work per ray, and that counting changes no
sample."""

import numpy as np
import pytest

from pathtrace.cameras import PerspectiveCamera
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
from pathtrace.scene import SceneBuilder, diffuse
from pathtrace.scene.environment import Environment
from pathtrace.bench.traversal_stats import traversal_stats

pytestmark = pytest.mark.specialised     # what the scenes' own programs walk


def test_one_sphere_is_tested_once_per_ray_without_a_tree(backend):
    """A scene this small has no tree (app/device/features.py: FLAT_MAX): each camera ray tests its one
    sphere and visits no node; with max depth 1 every sample is one ray."""
    b = SceneBuilder()
    b.add_sphere((0, 0, 0), 1.0, diffuse(0.5))
    scene = b.build("one", camera=PerspectiveCamera([0, 0, 4], [0, 0, 0], [0, 1, 0], 40.0),
                    environment=Environment.constant((1, 1, 1))).with_settings(max_depth=1, nee=False)
    stats = traversal_stats(backend, scene, 16, 9, 2)
    assert (stats.rays_per_sample, stats.nodes_per_ray, stats.primitives_per_ray) == (1.0, 0.0, 1.0)


def test_counts_of_a_tree_are_bounded_and_counting_changes_no_sample(backend):
    scene = load_scene("spheres8k-diffuse").with_settings(max_depth=8, russian_roulette="off", nee=True)
    stats = traversal_stats(backend, scene, 32, 18, 2)
    r = Renderer(backend, scene, 32, 18)
    nodes = len(r.compiled.bvh.nodes)
    assert 1.0 <= stats.rays_per_sample <= 15.0            # a camera ray; at most 8 bounces and 7 shadow rays
    assert 1.0 <= stats.nodes_per_ray < nodes and 0.0 < stats.primitives_per_ray < 8000
    r.add_samples(2)
    plain = r.mean()
    r.count_traversal(1)
    r.add_samples(2)
    assert np.array_equal(r.mean(), plain)                 # the same paths, only counted
    assert r.rays_traced() == round(stats.nodes_per_ray * stats.rays_per_sample * 32 * 18 * 2)
