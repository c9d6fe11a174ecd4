"""The continuation queue (render setting path_queue, kernels/integrator.cl PATH_QUEUE): paths that
go on past N vertices are stored and traced on by passes of continue_paths. Every sample draws the
same random numbers in the same order either way, so the image is the megakernel's up to the
order in which a pixel's samples are summed (within float32 rounding of the sums) and the rays
traced are exactly the same."""

from pathlib import Path

import numpy as np
import pytest

from pathtrace.rendering import queue_plans
from pathtrace.rendering import renderer as renderer_module
from pathtrace.errors import UserError
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
from pathtrace.rendering.choices import PATH_QUEUE_AUTO
from pathtrace.bench.traversal_stats import traversal_stats
from tests.commands import in_process

pytestmark = pytest.mark.specialised     # the queue is in the scenes' own programs alone

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


# Each scene's features with one queue depth, each depth on three of them: a depth and a scene
# make a program of their own (PATH_QUEUE), about 5 s of the suite on two cores each. The
# megakernels' programs are those of other tests (a Russian roulette rule is compiled in, the
# depth is not): the test scenes' with depth 8 and no roulette, tests/test_programs.py's, and
# tests/test_path_sort.py's of the same scenes and settings
@pytest.mark.parametrize("name, settings, depth", [
    ("teapot-textured", dict(max_depth=8, russian_roulette="off"), 1),    # textures, NEE, fixed depth
    ("cornell-box", dict(nee=False), 2),                                   # the report's estimator
    ("material-spheres", dict(max_depth=6, russian_roulette="off"), 1),   # glass and metals
    (str(SCENES / "media-fog.xml"), dict(max_depth=8, russian_roulette="off"), 2),   # media: hero channels
    (str(SCENES / "instances.xml"), dict(max_depth=8, russian_roulette="off"), 1),   # a two-level BVH
    (str(SCENES / "masks.xml"), dict(nee=False), 2),                       # alpha masks, roulette
])
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
    # the Cornell box's tree, whose counting programs without the queue tests/test_trace_split.py builds too
    scene = load_scene("cornell-box").with_settings(max_depth=8, russian_roulette="off")
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


@pytest.mark.parametrize("setting", ["2", "auto"])
def test_render_command_takes_the_setting(tmp_path, setting):
    """`pathtrace render --path-queue N` (or auto) renders the image it renders without."""
    from pathtrace.io.images import read_hdr
    images = []
    for value in ("0", setting):
        out = tmp_path / f"q{value}.exr"
        r = in_process("render", "cornell-box", "--size", "24x16", "--spp", "4", "--max-depth", "6", "--rr", "off",
                       "--path-queue", value, "-q", "-o", out)
        assert r.returncode == 0, r.stderr
        assert ("path queue auto: no queue" in r.stderr) == (value == "auto"), r.stderr
        images.append(read_hdr(out, "test"))
    np.testing.assert_allclose(images[1], images[0], rtol=1e-5, atol=1e-6)


def test_bands_of_rows_render_the_same(backend):
    """The viewer's launches cover bands of rows (pathtrace.rendering.launches.Progressive); a band's passes
    take only as many paths as its pixels can queue."""
    scene = load_scene("cornell-box").with_settings(max_depth=6, russian_roulette="off")
    plain = render(backend, scene, 0)
    r = Renderer(backend, scene.with_settings(path_queue=1), *SIZE)
    for first, end in ((0, 7), (7, 20), (20, SIZE[1])):
        r.add_samples(SPP, rows=(first, end))
    r.finish()
    assert_same_render(plain, (r.read_sum(), r._read("sum_sq"), r))


def test_auto_trials_each_plan_and_keeps_the_fastest(backend, monkeypatch, tmp_path):
    """path_queue "auto" times a trial render of each launch plan, twice, and keeps the one whose
    trial was fastest (on a clock that charges each plan its own cost per sample), then renders
    from an empty image. The verdict is kept: a second render of the scene runs no trials."""
    cost = {(0, False): 3.0, (1, True): 1.0, (1, False): 2.0}
    clock = [0.0]
    add_samples = Renderer.add_samples

    def timed_add_samples(self, count, *args, **kwargs):
        clock[0] += cost[self.queue_plan()] * count
        return add_samples(self, count, *args, **kwargs)

    monkeypatch.setattr(Renderer, "add_samples", timed_add_samples)
    monkeypatch.setattr(queue_plans.time, "perf_counter", lambda: clock[0])
    scene = load_scene("cornell-box").with_settings(max_depth=6, russian_roulette="off",
                                                   path_queue=PATH_QUEUE_AUTO)
    for cheapest in ((1, True), (1, False), (0, False)):
        monkeypatch.setenv("PATHTRACE_CACHE", str(tmp_path / str(cheapest)))
        cost[cheapest] = 0.5
        r = Renderer(backend, scene, *SIZE)
        r.choose_queue_plan(1000, trials=True)
        assert r.auto_plan == cheapest
        assert r.plan_seconds == {plan: c * queue_plans.TRIAL_SAMPLES for plan, c in cost.items()}
        assert r.samples == 0 and not r.read_sum().any()
        assert "trials of 16 spp" in r.describe_queue_plan()
        before = clock[0]
        again = Renderer(backend, scene, *SIZE)
        again.choose_queue_plan(1000, trials=True)
        assert again.auto_plan == cheapest and clock[0] == before and again.plan_cached
        assert again.describe_queue_plan().endswith("(as earlier trials chose)")
        cost[cheapest] = 4.0


def test_auto_keeps_its_trials_samples_where_asked(backend, monkeypatch, tmp_path):
    """With `first`, the trials draw sample indices first, first + 1, ... and their samples stay:
    the render goes on from them into the image of a fixed plan's render of as many samples.
    Two devices' trials (a group asked to keep up to what they draw) take indices after one
    another, so that no sample is drawn twice; asked to keep fewer, the trials' samples go."""
    from pathtrace.device.opencl import open_device
    from pathtrace.rendering.multidevice import DeviceGroup
    monkeypatch.setenv("PATHTRACE_CACHE", str(tmp_path))       # no verdict of earlier trials
    scene = load_scene("cornell-box").with_settings(max_depth=6, russian_roulette="off")
    auto = scene.with_settings(path_queue=PATH_QUEUE_AUTO)
    trials = queue_plans.TRIALS_SPP
    r = Renderer(backend, auto, *SIZE)
    r.choose_queue_plan(1000, trials=True, first=0)
    assert r.samples == trials and r.auto_plan in queue_plans.AUTO_PLANS
    r.add_samples(SPP)
    r.finish()
    assert_same_render(render(backend, scene, 0, trials + SPP), (r.read_sum(), r._read("sum_sq"), r))

    choose = Renderer.choose_queue_plan       # trials on PoCL too, on each device (no verdict kept)
    monkeypatch.setattr(Renderer, "choose_queue_plan",
                        lambda self, samples, trials=None, first=None: choose(self, samples, True, first))
    monkeypatch.setattr(queue_plans, "read_entry", lambda path: None)
    group = DeviceGroup([backend, open_device(backend.device)], auto, *SIZE)
    group.choose_queue_plans(1000, keep_up_to=2 * trials - 1)
    assert group.samples == 0 and all(r.plan_seconds for r in group.renderers)
    group = DeviceGroup([backend, open_device(backend.device)], auto, *SIZE)
    group.choose_queue_plans(1000, keep_up_to=2 * trials)
    assert group.samples_per_device() == [trials, trials]
    group.render(2 * trials + SPP)
    single = Renderer(backend, scene, *SIZE)
    single.add_samples(2 * trials + SPP)
    single.finish()
    np.testing.assert_allclose(group.mean(), single.mean(), rtol=1e-5, atol=1e-6)


def test_bench_keeps_autos_trials_in_its_first_round(backend, monkeypatch, tmp_path):
    """`bench` times auto's trials in its first round, their samples kept as a render keeps them:
    every round draws the row's samples, no more (the trials' 96 were thrown away)."""
    from pathtrace.bench import report
    monkeypatch.setenv("PATHTRACE_CACHE", str(tmp_path))       # no verdict of earlier trials
    choose = Renderer.choose_queue_plan       # trials on PoCL too
    monkeypatch.setattr(Renderer, "choose_queue_plan",
                        lambda self, samples, trials=None, first=None: choose(self, samples, True, first))
    drawn = []
    add_samples = Renderer.add_samples

    def counted(self, count=1, start=None, rows=None):
        if self.width == SIZE[0]:       # a band of rows draws its share of the samples
            drawn.append(count * (1 if rows is None else (rows[1] - rows[0]) / self.height))
        return add_samples(self, count, start, rows)
    monkeypatch.setattr(Renderer, "add_samples", counted)
    spp = queue_plans.TRIALS_SPP + SPP
    scene = load_scene("cornell-box").with_settings(path_queue=PATH_QUEUE_AUTO)
    result = report.measure([backend], scene, "depth8", *SIZE, spp, (None, None), rounds=2)
    assert sum(drawn) == pytest.approx(2 * spp) and len(result.render_rounds) == 2


def test_auto_leaves_out_a_queue_that_does_not_fit(backend, monkeypatch, tmp_path):
    """Where the queue's buffers would not fit in the device's memory, "auto" chooses among the
    other plans rather than refusing a render that fits without them."""
    check_fits = renderer_module.check_fits

    def queue_never_fits(device, buffers, what):
        if buffers["queue"] > renderer_module.PATH_RECORD.itemsize:
            raise UserError(f"{what}: too large")
        check_fits(device, buffers, what)

    monkeypatch.setattr(renderer_module, "check_fits", queue_never_fits)
    monkeypatch.setenv("PATHTRACE_CACHE", str(tmp_path))       # no verdict of earlier trials
    scene = load_scene("cornell-box").with_settings(max_depth=6, russian_roulette="off",
                                                   path_queue=PATH_QUEUE_AUTO)
    r = Renderer(backend, scene, *SIZE)
    r.choose_queue_plan(1000, trials=True)
    assert set(r.plan_seconds) == {(0, False), (1, False)} and r.auto_plan in r.plan_seconds
    r.add_samples(SPP)
    r.finish()
    assert_same_render(render(backend, scene, 0), (r.read_sum(), r._read("sum_sq"), r))


@pytest.mark.parametrize("plan", queue_plans.AUTO_PLANS)
def test_every_plan_renders_the_megakernels_image(backend, plan):
    """The plans "auto" chooses among, the queue's program with its queue unused included, render
    the image without the queue."""
    scene = load_scene("teapot-textured").with_settings(max_depth=8, russian_roulette="off")
    plain = render(backend, scene, 0)
    r = Renderer(backend, scene.with_settings(path_queue=PATH_QUEUE_AUTO), *SIZE)
    r.use_queue_plan(plan)
    assert r.queue_plan() == plan
    r.add_samples(SPP)
    r.finish()
    assert_same_render(plain, (r.read_sum(), r._read("sum_sq"), r))


def test_auto_runs_no_trials_on_cpus_or_for_short_renders(backend, monkeypatch, tmp_path):
    """Without trials, "auto" is no queue: on CPUs (PoCL), and for renders shorter than the trials;
    a change of the setting chooses again."""
    monkeypatch.setenv("PATHTRACE_CACHE", str(tmp_path))       # no verdict of earlier trials
    trials = []
    monkeypatch.setattr(Renderer, "add_samples", lambda self, *a, **k: trials.append(a))
    scene = load_scene("cornell-box").with_settings(path_queue=PATH_QUEUE_AUTO)
    r = Renderer(backend, scene, *SIZE)
    r.choose_queue_plan(10**6)
    r.choose_queue_plan(95, trials=True)
    assert r.queue_plan() == (0, False) and not trials and not r.plan_seconds
    assert r.describe_queue_plan() == "no queue"
    r.set_settings(path_queue=PATH_QUEUE_AUTO)
    assert r.auto_plan is None and not r.plan_seconds
    r.choose_queue_plan(96, trials=True)
    assert len(trials) == 6 and r.auto_plan in queue_plans.AUTO_PLANS


def test_the_viewer_refuses_auto():
    """The viewer runs no trials (its panel sets the queue): `view --path-queue auto` is one line."""
    r = in_process("view", "cornell-box", "--path-queue", "auto")
    assert r.returncode != 0 and "'auto' is not an integer" in r.stderr and "Traceback" not in r.stderr
