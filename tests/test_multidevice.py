"""Several devices in one render (app/rendering/multidevice.py): the merged image equals a one-device
render of the same samples, whatever the split; sample ranges are issued exactly once."""

import threading
import time

import numpy as np
import pytest

from pathtrace.cli.main import main
from pathtrace.compiler.compiled import CompiledScene
from pathtrace.device.opencl import open_device
from pathtrace.rendering.multidevice import DeviceGroup, SampleCounter
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene


@pytest.fixture(scope="module")
def scene():
    return load_scene("simple").with_settings(width=40, height=24)


def test_samples_split_by_index_give_the_same_image(backend, scene):
    """The random numbers are keyed on the sample's index: samples 0-15 added as 5-7, 0-4 and
    8-15 (in that order) give the image of one launch of 16."""
    whole = Renderer(backend, scene)
    whole.add_samples(16)
    parts = Renderer(backend, scene)
    for start, count in [(5, 3), (0, 5), (8, 8)]:
        parts.add_samples(count, start)
    np.testing.assert_allclose(parts.mean(), whole.mean(), rtol=1e-5, atol=1e-7)
    assert parts.samples == 16


def test_two_devices_give_the_one_device_image(backend, scene):
    """One device split twice (two contexts and queues on it): the merged sums equal a
    one-device render of the same samples, to float rounding, and both devices took part."""
    second = open_device(backend.device)
    for b in (backend, second):   # each builds the scene's kernels first, so that neither is left out
        Renderer(b, scene, 4, 4).add_samples(1)
    group = DeviceGroup([backend, second], scene)
    # the first device is slowed, so that it cannot take every sample before the second's thread
    # starts (on a loaded machine, as CI's two cores under the test workers, it once did)
    first = group.renderers[0]
    add_samples = first.add_samples
    first.add_samples = lambda *args: (time.sleep(0.02), add_samples(*args))[1]
    done = []
    group.render(48, on_progress=done.append, launch_seconds=0.01)
    single = Renderer(backend, scene)
    single.add_samples(48)
    assert group.samples == 48 and done[-1] == 48
    assert all(n > 0 for n in group.samples_per_device())
    np.testing.assert_allclose(group.mean(), single.mean(), rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(group.variance(), single.variance(), rtol=1e-3, atol=1e-6)
    assert group.rays_traced() == single.rays_traced()


def test_a_groups_renderers_are_made_at_once_and_build_one_tree(backend, scene, monkeypatch):
    """DeviceGroup makes each device's renderer in a thread of its own: both ask for the tree
    at once (a barrier that only two callers at once pass), and it is built once, by one of
    them, the other waiting for it."""
    both_asked = threading.Barrier(2, timeout=30)
    build_tree, _build_tree, built = CompiledScene.build_tree, CompiledScene._build_tree, []

    def asked_at_once(compiled, queue=None, when_bvh_built=None):
        both_asked.wait()
        build_tree(compiled, queue, when_bvh_built=when_bvh_built)

    def counted(compiled, queue, when_bvh_built=None):
        time.sleep(0.2)          # long enough for the other to reach the tree meanwhile
        built.append(threading.current_thread().name)
        _build_tree(compiled, queue, when_bvh_built)
    monkeypatch.setattr(CompiledScene, "build_tree", asked_at_once)
    monkeypatch.setattr(CompiledScene, "_build_tree", counted)
    group = DeviceGroup([backend, open_device(backend.device)], scene)
    assert len(built) == 1 and all(r.compiled.bvh is not None for r in group.renderers)
    group.render(2)
    assert group.samples == 2 and np.isfinite(group.mean()).all()


def test_a_tree_that_fails_is_built_once_for_a_group_and_its_error_raised(backend, scene, monkeypatch):
    """Both devices ask for the tree at once; its build fails: the one that waited raises that
    error rather than building it again, and the group raises it."""
    both_asked = threading.Barrier(2, timeout=30)
    build_tree, tries = CompiledScene.build_tree, []

    def asked_at_once(compiled, queue=None, when_bvh_built=None):
        both_asked.wait()
        build_tree(compiled, queue, when_bvh_built=when_bvh_built)

    def failing(compiled, queue, when_bvh_built=None):
        time.sleep(0.2)          # long enough for the other to wait for it
        tries.append(1)
        raise RuntimeError("out of memory")
    monkeypatch.setattr(CompiledScene, "build_tree", asked_at_once)
    monkeypatch.setattr(CompiledScene, "_build_tree", failing)
    with pytest.raises(RuntimeError, match="out of memory"):
        DeviceGroup([backend, open_device(backend.device)], scene)
    assert tries == [1]


def test_slow_samples_are_split_into_bands_of_rows(backend, scene, monkeypatch):
    """The first sample is split into FIRST_BANDS launches of rows, and a sample slower than the
    launch budget into bands too (so that Ctrl-C never waits for a whole image's sample); the
    image is the one of whole-image launches."""
    from pathtrace.rendering.multidevice import FIRST_BANDS, row_bands
    assert row_bands(24, 5) == [(0, 5), (5, 10), (10, 14), (14, 19), (19, 24)]
    assert row_bands(3, 16) == [(0, 1), (1, 2), (2, 3)]
    launches = []
    add = Renderer.add_samples
    monkeypatch.setattr(Renderer, "add_samples",
                        lambda self, count=1, start=None, rows=None: (launches.append((count, rows)),
                                                                      add(self, count, start, rows))[1])
    group = DeviceGroup([backend], scene)
    group.render(3, launch_seconds=1e-9)
    first = launches[:FIRST_BANDS]
    assert [rows for _, rows in first] == row_bands(24, FIRST_BANDS) and all(c == 1 for c, _ in first)
    assert len(launches) == FIRST_BANDS + 2 * 24 and all(rows[1] - rows[0] == 1 for _, rows in launches[FIRST_BANDS:])
    single = Renderer(backend, scene)
    add(single, 3)
    assert group.samples == 3
    np.testing.assert_allclose(group.mean(), single.mean(), rtol=1e-5, atol=1e-7)


def test_sample_counter_issues_every_index_once_across_threads():
    counter = SampleCounter(10_000)
    taken = [[] for _ in range(4)]

    def take(k):
        rate = 100.0 * (k + 1)
        while (t := counter.take(k, 7 * (k + 1), rate)) is not None:
            taken[k].append(t)

    threads = [threading.Thread(target=take, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    indices = np.concatenate([np.arange(s, s + c) for ranges in taken for s, c in ranges])
    np.testing.assert_array_equal(np.sort(indices), np.arange(10_000))


def test_near_the_end_a_device_takes_only_its_share():
    """With 10 samples left, a device of a third of the measured speed takes 4, not the 100
    its launch size asks for; the fast one then takes the other 6, which it draws in the time
    the slow one takes over its 4."""
    counter = SampleCounter(10)
    counter.take("fast", 0, rate=200.0, now=0.0)
    assert counter.take("slow", 100, rate=100.0, now=0.0) == (0, 4)
    assert counter.take("fast", 100, rate=200.0, now=0.0) == (4, 6)


def test_the_devices_end_together_counting_the_launches_they_have_yet_to_finish():
    """Two devices of one speed (100 samples/s): the first took 20 samples at 0 s, which it ends
    at 0.2 s. The second, asking at 0.1 s with 20 left, takes 15 (ending at 0.25 s), and the
    first the last 5 at 0.2 s (ending at 0.25 s too), where half of what was left, 10, would
    have left the first drawing alone from 0.2 to 0.3 s."""
    counter = SampleCounter(40)
    assert counter.take("a", 20, rate=100.0, now=0.0) == (0, 20)
    assert counter.take("b", 100, rate=100.0, now=0.1) == (20, 15)
    assert counter.take("a", 100, rate=100.0, now=0.2) == (35, 5)
    assert counter.take("b", 100, rate=100.0, now=0.25) is None


def test_a_device_error_stops_the_render_and_is_raised(backend, scene):
    group = DeviceGroup([backend, open_device(backend.device)], scene)

    def fail(*args):
        raise RuntimeError("device lost")

    group.renderers[1].add_samples = fail
    with pytest.raises(RuntimeError, match="device lost"):
        group.render(1000, launch_seconds=0.01)
    assert group.samples < 1000


def test_render_on_two_devices_from_the_command_line(tmp_path, capsys):
    out = tmp_path / "two.pfm"
    assert main(["render", "simple", "--size", "32x20", "--spp", "8", "--device", "cpu",
                 "--device", "cpu:0", "-o", str(out), "-q"]) == 0
    assert capsys.readouterr().err.count("device: ") == 2 and out.stat().st_size > 0


def test_the_viewer_refuses_several_devices(capsys):
    assert main(["view", "simple", "--device", "cpu", "--device", "cpu"]) == 1
    err = capsys.readouterr().err
    assert "the viewer renders on one device" in err and len(err.strip().splitlines()) == 1


def test_an_unmatched_nth_device_is_one_line(capsys):
    assert main(["render", "simple", "--device", "cpu:7", "-o", "x.png", "-q"]) == 1
    assert "no OpenCL device matches 'cpu:7'" in capsys.readouterr().err


def test_every_device_is_checked_before_any_renderer_allocates(backend, scene, monkeypatch):
    """A group whose second device cannot hold the scene is refused in one line before any of
    its renderers is made: the renderers, made at once, would otherwise upload on the first."""
    import pathtrace.device.opencl as opencl
    from pathtrace.errors import UserError
    checked, made, check_fits = [], [], opencl.check_fits

    def second_refuses(device, buffers, name):
        checked.append(device)
        if len(checked) == 2:
            raise UserError(f"{name} needs more memory than the second device has")
        check_fits(device, buffers, name)
    monkeypatch.setattr(opencl, "check_fits", second_refuses)
    monkeypatch.setattr(Renderer, "__init__", lambda *args, **kwargs: made.append(args))
    with pytest.raises(UserError, match="than the second device has"):
        DeviceGroup([backend, open_device(backend.device)], scene)
    assert len(checked) == 2 and made == []
