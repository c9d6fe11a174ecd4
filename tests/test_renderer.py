"""The progressive Renderer: determinism, seeds, resets, and the built-in scenes."""

import numpy as np
import pytest

from app.scene.builtin import BUILTIN_SCENES
from app.renderer import Renderer
from app.scene import load_scene
from tests.stats import z_test


def accumulate(renderer, launches):
    renderer.reset()
    for n in launches:
        renderer.add_samples(n)
    renderer.finish()
    return renderer.mean(), renderer.variance() / renderer.samples


@pytest.fixture(scope="module")
def simple(backend):
    return Renderer(backend, load_scene("simple"), 48, 27)


def test_same_seed_same_image_whatever_the_launches(simple):
    a, _ = accumulate(simple, [16])
    b, _ = accumulate(simple, [16])
    c, _ = accumulate(simple, [1, 3, 4, 8])
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(a, c, rtol=1e-5, atol=1e-6)   # only the summation order differs


def test_another_seed_other_noise_same_mean(simple):
    a, va = accumulate(simple, [64] * 4)
    simple.set_settings(seed=12345)
    b, vb = accumulate(simple, [64] * 4)
    simple.set_settings(seed=0)
    assert np.mean(a != b) > 0.5
    ok, p, threshold = z_test(a, va + vb, b, block=3)
    assert ok, (p, threshold)


def test_reset_restarts_the_average(simple):
    accumulate(simple, [4])
    simple.reset()
    assert simple.samples == 0 and np.all(simple.mean() == 0)


@pytest.mark.parametrize("name", list(BUILTIN_SCENES))
def test_builtin_scenes_render_finite_and_plausible(backend, name):
    scene = load_scene(name)
    r = Renderer(backend, scene, 32, 18)
    r.add_samples(2)
    r.finish()
    image = r.mean()
    assert np.all(np.isfinite(image)) and image.min() >= 0 and image.mean() > 0.05
