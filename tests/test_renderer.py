"""The progressive Renderer: determinism, seeds, resets, and the built-in scenes."""

import numpy as np
import pyopencl as cl
import pytest

from pathtrace.cameras import PerspectiveCamera
from pathtrace.scene.environment import Environment
from pathtrace.rendering.renderer import Renderer, image_buffers
from pathtrace.scene import RenderSettings, SceneBuilder, diffuse, load_scene
from pathtrace.scene.builtin import BUILTIN_SCENES
from tests.stats import z_test
from tests.test_bdpt import pool_scene


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


def test_a_reset_image_handed_out_holds_zeros(simple):
    """As a window's display and denoiser read it, through buffer() and read_async(), after a
    reset and before any launch."""
    accumulate(simple, [4])
    simple.reset()
    out = np.ones((simple.height, simple.width, 4), np.float32)
    cl.enqueue_copy(simple.backend.queue, out, simple.buffer("sum"))
    assert np.all(out == 0)
    accumulate(simple, [4])
    simple.reset()
    event, (read,) = simple.read_async(("sum",))       # as the denoiser reads it
    event.wait()
    assert np.all(read == 0)


def test_resets_in_a_row_clear_once_at_the_size_used(backend, monkeypatch):
    """A viewer's renderer is made at the scene's size and resized to its first preview before
    it launches: only the preview's images are cleared, once."""
    cleared = []
    fill = cl.enqueue_fill_buffer
    monkeypatch.setattr(cl, "enqueue_fill_buffer", lambda queue, mem, pattern, offset, size, **kw: (
        cleared.append((mem, size)), fill(queue, mem, pattern, offset, size, **kw))[1])
    r = Renderer(backend, load_scene("simple"), 64, 48)
    r.resize(16, 12)
    r.reset()
    r.add_samples(1)
    r.finish()
    images = [r.buffer(name) for name in image_buffers(r.aovs)]
    assert not [size for _, size in cleared if size == 64 * 48 * 16]
    assert sorted(id(mem) for mem, _ in cleared if any(mem is b for b in images)) == sorted(map(id, images))
    assert r.samples == 1 and r.mean().mean() > 0
    def image_fills():
        return sum(any(mem is b for b in images) for mem, _ in cleared)
    before = image_fills()
    r.reset()
    r.finish()          # as a timed trial render waits for the clearing before its clock starts
    assert image_fills() == before + len(images)
    r.add_samples(1)
    r.finish()
    assert image_fills() == before + len(images)


@pytest.mark.parametrize("name", list(BUILTIN_SCENES))
def test_builtin_scenes_render_finite_and_plausible(backend, name):
    scene = load_scene(name)
    r = Renderer(backend, scene, 32, 18)
    r.add_samples(2)
    r.finish()
    image = r.mean()
    assert np.all(np.isfinite(image)) and image.min() >= 0 and image.mean() > 0.05


def poisoned_simple():
    """`simple` with its ground's albedo NaN, as a bug or a value beyond float32 might make it."""
    scene = load_scene("simple")
    ground = scene.sphere_material[0]
    scene.materials.rows["p0"][ground, :3] = np.nan
    return scene


def test_nan_samples_are_left_out_and_counted(backend):
    """A NaN sample never poisons its pixel: it counts as black and is reported (#12)."""
    r = Renderer(backend, poisoned_simple(), 32, 18)
    r.add_samples(4)
    image = r.mean()
    assert np.all(np.isfinite(image))
    dropped = r.dropped_samples()
    assert 0 < dropped < 4 * 32 * 18          # the ground's samples, not the sky's
    clean = Renderer(backend, load_scene("simple"), 32, 18)
    clean.add_samples(4)
    assert clean.dropped_samples() == 0
    sky = image[0]                               # the top row sees only the sky
    np.testing.assert_allclose(sky, clean.mean()[0], rtol=1e-6)


def test_the_command_line_reports_nan_samples(monkeypatch, tmp_path, capsys):
    import pathtrace.cli.main as cli
    import pathtrace.scene
    monkeypatch.setattr(pathtrace.scene, "load_scene", lambda name: poisoned_simple())
    assert cli.main(["render", "simple", "-o", str(tmp_path / "a.png"), "--size", "16x9", "--spp", "2", "-q"]) == 0
    assert "samples were NaN or infinite and were left out (as black)" in capsys.readouterr().err


def test_an_environment_edit_updates_the_light_choice(backend):
    """The light table weighs the environment by its power: one that starts black is never
    sampled, and turning it up (Renderer.set_environment, as the viewer's panel does) makes it
    a light, so next-event estimation samples it."""
    from pathtrace.scene import emitter
    b = SceneBuilder()
    b.add_sphere((0, 0, 0), 1.0, diffuse(0.5))
    b.add_sphere((0, 4, 0), 0.5, emitter(10.0))
    scene = b.build("lights", camera=PerspectiveCamera([0, 0, 5], [0, 0, 0], [0, 1, 0], 40.0),
                    environment=Environment.constant((1, 1, 1), intensity=0.0),
                    settings=RenderSettings(width=16, height=16))
    r = Renderer(backend, scene)
    assert r.lights.env_pick == 0.0
    env = r.environment
    env.intensity = 1.0
    r.set_environment(env)
    assert 0.0 < r.lights.env_pick < 1.0 and r.params(1)["env_pick"] == r.lights.env_pick


def test_sums_stay_exact_over_millions_of_samples(backend):
    """A pixel that sees only a sky of radiance 0.1 (not a float32 number: every sample adds a
    rounded value) gets 2^22 samples, in launches of 64. Plain float32 sums, as before, gave a
    mean of 0.10099 at 2^25 samples: each addition rounds by up to half an ulp of a growing
    total, and past a total of 2^18, where the ulp is 1/32, a launch's 6.4 is added as 6.40625:
    plain sums of these launches give 0.100062, 200 times this test's tolerance. The compensated running sums keep the mean to
    within the rounding of a launch's 64 samples (2.4e-6 at worst), and the sample count and the
    rays traced exact. (The launches, 65,536 of one pixel, are what this test's time goes on.)"""
    b = SceneBuilder()
    b.add_sphere((0, 0, 10), 1.0, diffuse(0.5))              # behind the camera
    scene = b.build("sky", camera=PerspectiveCamera([0, 0, 0], [0, 0, -1], [0, 1, 0], 1.0),
                    environment=Environment.constant((0.1, 0.1, 0.1)),
                    settings=RenderSettings(width=1, height=1, nee=False))
    r = Renderer(backend, scene)
    launches, per_launch = 4, 2 ** 20
    for _ in range(launches):
        r.add_samples(per_launch)
    r.finish()
    n = launches * per_launch
    np.testing.assert_allclose(r.mean(), np.float32(0.1), rtol=3e-6)
    assert r.read_sum()[0, 0, 3] == n and r.dropped_samples() == 0 and r.rays_traced() == n
    np.testing.assert_allclose(r.variance(), 0.0, atol=1e-8)


@pytest.mark.parametrize("settings", [{"integrator": "path", "path_queue": 1}, {"integrator": "bdpt", "photon_radius": 0.0},
                                      {"integrator": "bdpt", "photon_radius": 0.05}],
                         ids=["path-queue", "bdpt", "bdpt-photons"])
def test_a_render_reads_nothing_it_has_not_written(backend, monkeypatch, settings):
    """A GPU's fresh buffers hold whatever was there, where PoCL's are zeroed: with every buffer
    the renderer makes without data filled with random bytes first, the image is the one of
    zeroed buffers (the path queue's, BDPT's splat film and the photon map included; BDPT's
    splats are added by atomics in any order, so to float rounding)."""
    import pyopencl as cl
    scene = pool_scene().with_settings(seed=5, **settings)

    def image():
        r = Renderer(backend, scene, 24, 16)
        r.add_samples(4)
        r.finish()
        assert r.dropped_samples() == 0
        return r.mean()
    clean = image()
    rng, buffer = np.random.default_rng(2), cl.Buffer

    def garbage(context, flags, size=0, hostbuf=None):
        buf = buffer(context, flags, size, hostbuf)
        if hostbuf is None and size:
            cl.enqueue_copy(backend.queue, buf, rng.integers(0, 256, size, dtype=np.uint8))
        return buf
    monkeypatch.setattr(cl, "Buffer", garbage)
    assert np.allclose(image(), clean, rtol=1e-5, atol=1e-7)
