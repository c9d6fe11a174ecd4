"""The continuation queue sorted by ray (render setting path_sort, kernels/path_sort.cl PATH_SORT):
the queue's paths wait before they trace their next ray, keyed by its direction bin and the cell
of the primitive it leaves, and each pass of continue_paths takes them in the order of a counting
sort by key. A path's random numbers travel with it, so the image is the megakernel's up to the
order in which a pixel's samples are summed, and the rays traced are the same."""

import numpy as np
import pyopencl as cl
import pytest

from pathtrace.bench.divergence_stats import divergence_stats
from pathtrace.device.features import SORT_CELLS, Features
from pathtrace.rendering import renderer as renderer_module
from pathtrace.rendering.choices import PATH_QUEUE_AUTO
from pathtrace.rendering.path_sort import PathSort
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
from tests.commands import in_process
from tests.stats import z_test
from tests.test_path_queue import SCENES, SIZE, SPP, assert_same_render, render

pytestmark = pytest.mark.specialised     # the queue is in the scenes' own programs alone


def sorted_render(backend, scene, path_queue=1, spp=SPP):
    return render(backend, scene.with_settings(path_sort=True), path_queue, spp)


@pytest.mark.parametrize("name, settings, depth", [
    ("material-spheres", dict(max_depth=6, russian_roulette="off"), 1),  # glass and metals
    ("teapot-textured", dict(max_depth=8, russian_roulette="off"), 2),   # textures
    (str(SCENES / "media-fog.xml"), dict(max_depth=8, russian_roulette="off"), 1),   # media: the medium the waiting ray crosses
    (str(SCENES / "instances.xml"), dict(max_depth=8, russian_roulette="off"), 1),   # instances (flattened: below)
    (str(SCENES / "masks.xml"), dict(nee=False), 1),                     # alpha masks, the report's estimator
])
def test_sorted_paths_render_the_megakernels_image(backend, name, settings, depth):
    scene = load_scene(name).with_settings(**settings)
    plain = render(backend, scene, 0)
    assert plain[0][..., 3].sum() == SIZE[0] * SIZE[1] * SPP
    assert_same_render(plain, sorted_render(backend, scene, depth))


def test_a_two_level_scenes_sorted_paths_render_the_megakernels_image(backend, monkeypatch):
    """Instances kept in a two-level BVH: a ray's key takes the primitive it leaves within its
    object (kernels/path_sort.cl: sort_key)."""
    from pathtrace.scene import instances
    monkeypatch.setattr(instances, "FLATTEN_MAX", -1)
    scene = load_scene(str(SCENES / "instances.xml")).with_settings(max_depth=8, russian_roulette="off")
    plain = render(backend, scene, 0)
    assert plain[2].compiled.two_level
    assert_same_render(plain, sorted_render(backend, scene))


def test_paths_that_find_the_sorted_queue_full_go_on_where_they_are(backend, monkeypatch):
    scene = load_scene("material-spheres").with_settings(max_depth=6, russian_roulette="off")
    plain = render(backend, scene, 0)
    monkeypatch.setattr(renderer_module, "MAX_QUEUED", 16)
    assert_same_render(plain, sorted_render(backend, scene))


def test_the_sorted_render_agrees_with_the_unsorted_one_in_expectation(backend):
    """Independent samples (other seeds) of the sorted and the unsorted queue: the same
    expectation pixel by pixel, by the variance of each mean."""
    scene = load_scene("material-spheres").with_settings(max_depth=6, russian_roulette="off")
    images = []
    for seed, sort in ((0, False), (1, True)):
        r = Renderer(backend, scene.with_settings(path_queue=1, path_sort=sort, seed=seed), 32, 24)
        r.add_samples(64)
        images.append((r.mean(), r.variance() / r.samples))
    (m, v), (ref, ref_v) = images
    assert not np.array_equal(m, ref)                      # the seeds drew other samples
    ok, p, threshold = z_test(m, v, ref, ref_v, block=4)
    assert ok, (p, threshold)


def read_ints(backend, r, name) -> np.ndarray:
    buffer = r.buffer(name)
    out = np.empty(buffer.size // 4, np.int32)
    cl.enqueue_copy(backend.queue, out, buffer)
    return out


def ray_keys(d: np.ndarray, prims: np.ndarray, shift: int) -> np.ndarray:
    """kernels/path_sort.cl's sort_key: the direction bin (the cube face of d's largest component,
    the quadrant within it) times SORT_CELLS + the cell of the primitive left."""
    a = np.abs(d)
    axis = np.where((a[:, 0] >= a[:, 1]) & (a[:, 0] >= a[:, 2]), 0, np.where(a[:, 1] >= a[:, 2], 1, 2))
    major = d[np.arange(len(d)), axis]
    u, v = np.where(axis == 0, d[:, 1], d[:, 0]), np.where(axis == 2, d[:, 1], d[:, 2])
    direction = (2 * axis + (major < 0)) * 4 + (u < 0) + 2 * (v < 0)
    return direction * SORT_CELLS + np.where(prims < 0, 0, np.minimum(prims >> shift, SORT_CELLS - 1))


@pytest.mark.parametrize("shift", [None, 3])
def test_each_pass_takes_its_queue_in_the_order_of_the_keys(backend, monkeypatch, shift):
    """After a launch, `order` holds the sort of the queue that the last pass took: a permutation
    of its slots whose keys do not decrease, each key counted as often as it occurs, and each key
    the ray's that the path stored (its direction, the primitive it leaves), by sort_key's rule:
    with the scene's own cells (one primitive each here) and with cells of 8."""
    if shift is not None:
        monkeypatch.setattr(PathSort, "sort_shift", lambda self: shift)
    scene = load_scene("material-spheres").with_settings(max_depth=6, russian_roulette="off")
    _, _, r = sorted_render(backend, scene)
    k, capacity, keys_of = r.queue_passes(), r.queue_capacity(*SIZE), r.sort_keys()
    count = min(int(read_ints(backend, r, "counters")[k]), capacity)
    assert count > 100                                     # paths went on to the last pass
    order = read_ints(backend, r, "order")[:count]
    keys = read_ints(backend, r, ("keys", "keys_next")[k % 2])[:count]
    assert np.array_equal(np.sort(order), np.arange(count))
    assert np.all(np.diff(keys[order]) >= 0)
    assert len(np.unique(keys)) > 20                       # rays of many directions and places waited
    counts = read_ints(backend, r, "key_counts")[k * keys_of:(k + 1) * keys_of]
    assert np.array_equal(counts, np.bincount(keys, minlength=keys_of))
    # the queue's structure of arrays (kernels/path_queue.cl: store_path): field f of slot s at f * capacity + s
    fields = np.empty((renderer_module.PATH_RECORD.itemsize // 16, capacity, 4), np.float32)
    cl.enqueue_copy(backend.queue, fields, r.buffer(("queue", "queue_next")[k % 2]))
    names = renderer_module.PATH_RECORD.names
    d = fields[names.index("d"), :count, :3]
    prims = fields[names.index("prev_x"), :count, 3].view(np.int32)
    assert r.sort_shift() == (shift or 0) and np.array_equal(keys, ray_keys(d, prims, r.sort_shift()))


def test_a_warp_of_a_sorted_pass_takes_rays_of_fewer_keys(backend):
    """The divergence records follow the queue's passes: the same paths, hence the same lanes at
    each iteration and branch, as the megakernel's; and the 32 paths a warp of the last pass takes
    have fewer keys and direction bins among them than 32 taken in the order they were queued."""
    scene = load_scene("material-spheres").with_settings(max_depth=5, russian_roulette="off")
    plain, queued, ordered = (divergence_stats(backend, scene.with_settings(path_queue=q, path_sort=s), 32, 24, 2)
                              for q, s in ((0, False), (1, False), (1, True)))
    lanes = [{b.name: b.lanes for b in s.branches} for s in (plain, queued, ordered)]
    assert lanes[0] == lanes[1] == lanes[2]
    _, _, r = sorted_render(backend, scene)
    k = r.queue_passes()
    count = min(int(read_ints(backend, r, "counters")[k]), r.queue_capacity(*SIZE))
    keys = read_ints(backend, r, ("keys", "keys_next")[k % 2])[:count]
    order = read_ints(backend, r, "order")[:count]
    directions = keys // SORT_CELLS
    warps = range(0, count // 32 * 32, 32)
    assert len(warps) >= 5
    for of, ratio in ((keys, 0.8), (directions, 0.5)):     # here 12.4 against 22.7, 3.7 against 15.0
        per_warp = np.mean([len(np.unique(of[w:w + 32])) for w in warps])
        sorted_per_warp = np.mean([len(np.unique(of[order[w:w + 32]])) for w in warps])
        assert sorted_per_warp < ratio * per_warp, (sorted_per_warp, per_warp)


def test_the_setting_sizes_the_sort(backend):
    scene = load_scene("cornell-box").with_settings(max_depth=5, russian_roulette="off", path_queue=1)
    r = Renderer(backend, scene, *SIZE)
    unsorted = r.buffer("queue").size
    assert r.buffer("order").size == 4
    r.set_settings(path_sort=True)
    capacity = r.queue_capacity(*SIZE)
    assert r.buffer("queue").size == renderer_module.PATH_RECORD.itemsize * capacity == unsorted
    assert r.buffer("order").size == r.buffer("keys_next").size == 4 * capacity
    assert r.queue_passes() == 5 - 1 - 1          # vertices 2 to 4 shaded a pass each, then the last
    assert r.buffer("key_counts").size == 4 * r.sort_keys() * (r.queue_passes() + 1)
    r.set_settings(max_depth=7)
    assert r.queue_passes() == 5 and r.buffer("counters").size == 4 * (5 + 2)
    r.set_settings(max_depth=0, russian_roulette="throughput")
    assert r.queue_passes() == renderer_module.SORT_PASSES
    r.set_settings(path_queue=0)        # no queue, no sort
    assert not r.sorts_queue() and r.buffer("order").size == 4


def test_auto_keeps_the_sorted_queues_verdict_apart(backend):
    """path_queue "auto" remembers which plan its trials chose (queue_plans.py); with path_sort its
    queue plan is the sorted one, which may win where the unsorted one lost."""
    r = Renderer(backend, load_scene("cornell-box").with_settings(path_queue=PATH_QUEUE_AUTO), *SIZE)
    unsorted = r._plan_verdict_path()
    r.set_settings(path_sort=True)
    assert not r.sorts_queue()                 # no plan chosen yet: no queue, no sort
    assert r._plan_verdict_path() != unsorted


@pytest.mark.parametrize("primitives, shift", [(1, 0), (SORT_CELLS, 0), (SORT_CELLS + 1, 1), (103_830, 6),
                                               (409_602, 8)])
def test_a_keys_cells_hold_the_scenes_primitives_in_at_most_sort_cells(primitives, shift):
    from types import SimpleNamespace
    holder = SimpleNamespace(compiled=SimpleNamespace(num_spheres=1, num_triangles=primitives - 1))
    assert PathSort.sort_shift(holder) == shift
    assert -(-primitives // 2 ** shift) <= SORT_CELLS


def test_programs_without_the_setting_compile_no_sort():
    assert "PATH_SORT" not in Features(path_queue=1).defines()
    assert "PATH_SORT" in Features(path_queue=1, path_sort=True).defines()


def test_the_sort_needs_the_queue(tmp_path):
    r = in_process("render", "cornell-box", "--size", "8x8", "--spp", "1", "--path-sort", "-q", "-o", tmp_path / "x.exr")
    assert r.returncode != 0 and not (tmp_path / "x.exr").exists()
    assert r.stderr.strip().splitlines()[-1].endswith("--path-sort sorts the continuation queue's paths: "
                                                      "give --path-queue N (N >= 1) too")   # (view has no auto)
    r = in_process("bench", "--device", "cpu", "--scenes", "cornell-box", "--path-sort")
    assert r.returncode != 0 and "--path-sort sorts the continuation queue's paths" in r.stderr


def test_render_command_takes_the_setting(tmp_path):
    """`pathtrace render --path-queue 1 --path-sort` renders the image it renders without."""
    from pathtrace.io.images import read_hdr
    images = []
    for extra in ((), ("--path-queue", "1", "--path-sort")):
        out = tmp_path / f"s{len(extra)}.exr"
        r = in_process("render", "cornell-box", "--size", "24x16", "--spp", "4", "--max-depth", "6", "--rr", "off",
                       *extra, "-q", "-o", out)
        assert r.returncode == 0, r.stderr
        images.append(read_hdr(out, "test"))
    np.testing.assert_allclose(images[1], images[0], rtol=1e-5, atol=1e-6)
