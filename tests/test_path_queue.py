"""The continuation queue (render setting path_queue, kernels/integrator.cl PATH_QUEUE): paths that
go on past N vertices are stored and traced on by passes of continue_paths. Every sample draws the
same random numbers in the same order either way, so the image is the megakernel's up to the
order in which a pixel's samples are summed (within float32 rounding of the sums) and the rays
traced are exactly the same."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pathtrace import renderer as renderer_module
from pathtrace.renderer import Renderer
from pathtrace.scene import load_scene
from pathtrace.traversal_stats import traversal_stats

SCENES = Path(__file__).parent / "scenes"
SIZE = (40, 24)
SPP = 6


def render(backend, scene, path_queue, spp=SPP):
    r = Renderer(backend, scene.with_settings(path_queue=path_queue), *SIZE)
    r.add_samples(spp)
    r.finish()
    return r.read_sum(), r._read("sum_sq"), r


def assert_same_render(a, b):
    sum_a, sq_a, _ = a
    sum_b, sq_b, _ = b
    assert np.array_equal(sum_a[..., 3], sum_b[..., 3])          # the samples kept
    assert np.array_equal(sq_a[..., 3], sq_b[..., 3])            # the rays traced, per pixel
    scale = max(float(np.abs(sum_a[..., :3]).max()), 1e-6)
    # a pixel's samples summed in another order: a few float32 roundings of the sum
    np.testing.assert_allclose(sum_b[..., :3], sum_a[..., :3], rtol=1e-5, atol=1e-6 * scale)
    np.testing.assert_allclose(sq_b[..., :3], sq_a[..., :3], rtol=1e-5,
                               atol=1e-6 * max(float(np.abs(sq_a[..., :3]).max()), 1e-6))


@pytest.mark.parametrize("name, settings", [
    ("teapot-textured", dict(max_depth=8, russian_roulette="off")),    # textures, NEE, fixed depth
    ("cornell-box", dict(nee=False)),                                   # the report's estimator
    ("material-spheres", dict()),                                       # glass and metals, roulette
    (str(SCENES / "media-fog.xml"), dict()),                            # media: hero channels
    (str(SCENES / "instances.xml"), dict()),                            # a two-level BVH
    (str(SCENES / "masks.xml"), dict()),                                # alpha masks
])
@pytest.mark.parametrize("depth", [1, 2])
def test_queued_paths_render_the_megakernels_image(backend, name, settings, depth):
    scene = load_scene(name).with_settings(**settings)
    plain = render(backend, scene, 0)
    queued = render(backend, scene, depth)
    assert plain[0][..., 3].sum() == SIZE[0] * SIZE[1] * SPP      # every sample finite and kept
    assert_same_render(plain, queued)


def test_paths_that_find_the_queue_full_go_on_in_place(backend, monkeypatch):
    scene = load_scene("cornell-box").with_settings(max_depth=6, russian_roulette="off")
    plain = render(backend, scene, 0)
    monkeypatch.setattr(renderer_module, "MAX_QUEUED", 16)
    queued = render(backend, scene, 1)
    assert queued[2].queue_capacity(*SIZE) == 16
    assert_same_render(plain, queued)


def test_more_vertices_than_passes_end_in_the_last_pass(backend, monkeypatch):
    """Unlimited depth (Russian roulette alone ends paths): after QUEUE_PASSES passes of one
    vertex, the last pass traces the paths to their ends, however long."""
    monkeypatch.setattr(renderer_module, "QUEUE_PASSES", 1)
    scene = load_scene("cornell-box").with_settings(max_depth=0, russian_roulette="throughput")
    plain = render(backend, scene, 0, spp=1)
    queued = render(backend, scene, 1, spp=1)
    # a path with vertices beyond the first (1), the pass's (2) and one more traced 7 rays or more
    assert queued[1][..., 3].max() >= 7
    assert_same_render(plain, queued)


def test_the_queue_counts_the_same_traversal_work(backend):
    scene = load_scene("teapot-sky").with_settings(max_depth=8, russian_roulette="off")
    plain = traversal_stats(backend, scene, *SIZE, 2)
    queued = traversal_stats(backend, scene.with_settings(path_queue=1), *SIZE, 2)
    assert (queued.rays_per_sample, queued.nodes_per_ray, queued.primitives_per_ray) == \
        (plain.rays_per_sample, plain.nodes_per_ray, plain.primitives_per_ray)


def test_changing_the_setting_sizes_the_queue_and_renders_the_same(backend):
    scene = load_scene("cornell-box").with_settings(max_depth=5, russian_roulette="off")
    plain = render(backend, scene, 0)
    r = Renderer(backend, scene, *SIZE)
    r.set_settings(path_queue=2)
    assert r.buffer("queue").size == renderer_module.PATH_RECORD.itemsize * r.queue_capacity(*SIZE) > 128
    r.add_samples(SPP)
    r.finish()
    assert_same_render(plain, (r.read_sum(), r._read("sum_sq"), r))
    r.set_settings(path_queue=0)
    assert r.buffer("queue").size == renderer_module.PATH_RECORD.itemsize


def test_render_command_takes_the_setting(tmp_path):
    """`pathtrace render --path-queue N` renders the image it renders without."""
    from pathtrace.image_io import read_hdr
    images = []
    for depth in ("0", "2"):
        out = tmp_path / f"q{depth}.exr"
        r = subprocess.run([sys.executable, "-m", "pathtrace", "render", "cornell-box", "--size", "24x16",
                            "--spp", "4", "--max-depth", "6", "--rr", "off", "--path-queue", depth, "-q",
                            "-o", str(out)], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        images.append(read_hdr(out, "test"))
    np.testing.assert_allclose(images[1], images[0], rtol=1e-5, atol=1e-6)


def test_bands_of_rows_render_the_same(backend):
    """The viewer's launches cover bands of rows (pathtrace.launches.Progressive); a band's passes
    take only as many paths as its pixels can queue."""
    scene = load_scene("cornell-box").with_settings(max_depth=6, russian_roulette="off")
    plain = render(backend, scene, 0)
    r = Renderer(backend, scene.with_settings(path_queue=1), *SIZE)
    for first, end in ((0, 7), (7, 20), (20, SIZE[1])):
        r.add_samples(SPP, rows=(first, end))
    r.finish()
    assert_same_render(plain, (r.read_sum(), r._read("sum_sq"), r))
