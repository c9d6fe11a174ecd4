"""The viewer's way to the screen, headless: what pathtrace.viewer.display brings to the host (the float sums,
or kernels/display.cl's half floats) against the mean computed on the host; and
pathtrace.rendering.launches.Progressive, which feeds a renderer in bands without ever waiting for it."""

import threading

import numpy as np
import pyopencl as cl
import pytest

from pathtrace.viewer.display import MODES, Display
from pathtrace.rendering.launches import Progressive
from pathtrace.rendering.renderer import Renderer, per_pixel_mean
from pathtrace.scene import load_scene


@pytest.fixture(scope="module")
def renderer(backend):
    return Renderer(backend, load_scene("simple"), 40, 24)


@pytest.mark.parametrize("mode", MODES)
def test_each_display_way_gives_the_per_pixel_mean(backend, mode):
    """rgb / a of what reaches the host is the mean of each pixel (to half precision for half
    floats); a pixel with no sample yet is black; beyond half's range, half floats clamp to its
    largest value rather than become infinite."""
    h, w = 7, 9
    rng = np.random.default_rng(1)
    sums = np.concatenate([rng.uniform(0, 50, (h, w, 3)), rng.integers(1, 9, (h, w, 1))], -1).astype(np.float32)
    sums[0, 0, 3] = 0.0
    sums[1, 1, :3], sums[1, 1, 3] = 1e9, 1.0
    buffer = cl.Buffer(backend.context, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR, hostbuf=sums)
    display, got = Display(backend, mode), []
    display.request(buffer, w, h)
    display.wait(lambda pixels: got.append(pixels.astype(np.float64)))
    a = got[0][..., 3:]
    mean = np.divide(got[0][..., :3], a, out=np.zeros((h, w, 3)), where=a > 0)
    expected = per_pixel_mean(sums)
    if mode == "half":
        expected[1, 1] = 65504.0
    np.testing.assert_allclose(mean, expected, rtol=1e-3)
    assert np.all(mean[0, 0] == 0)


def test_the_default_way_follows_the_memory(backend):
    shared = backend.device.device.host_unified_memory
    assert Display(backend).mode == ("sums" if shared else "half")


def test_bands_add_the_samples_one_launch_would(backend, renderer):
    """A pass split into bands of rows draws the same sample indices: bit-identical sums."""
    r = renderer
    r.reset()
    r.add_samples(3)
    whole = r.read_sum().copy()
    r.reset()
    for first in range(0, r.height, 5):
        r.add_samples(3, rows=(first, min(first + 5, r.height)))
    assert r.samples == 3
    np.testing.assert_array_equal(r.read_sum(), whole)


def test_progressive_never_waits_and_counts_whole_passes(backend, renderer):
    """With the device held up (a barrier on an event only the test completes), step() still
    returns, having queued its launches, and counts nothing as done; released, the passes it
    finished hold exactly the samples whole-image launches would have added."""
    r = renderer
    r.reset()
    p = Progressive(r, budget=1e-4)           # tiny launches: several bands a pass
    gate = cl.UserEvent(backend.context)
    cl.enqueue_barrier(backend.queue, wait_for=[gate])
    returned = threading.Event()
    worker = threading.Thread(target=lambda: (p.step(), returned.set()))
    worker.start()
    assert returned.wait(10), "step() waited for the device"
    assert p.passes_done == 0 and p.rows_done == 0
    gate.set_status(cl.command_execution_status.COMPLETE)
    worker.join()
    while p.passes_done < 2:
        p.step()
    p.finish_pass()
    assert p.passes_done == r.samples >= 2 and p.progress == 0.0
    counts = r.read_sum()[..., 3]
    assert np.all(counts == r.samples)
    banded = r.read_sum().copy()
    reference = Renderer(backend, r.compiled, r.width, r.height)
    reference.add_samples(r.samples)
    np.testing.assert_allclose(reference.read_sum(), banded, rtol=1e-5, atol=1e-6)


def test_a_reset_restarts_the_pass(backend, renderer):
    r = renderer
    p = Progressive(r, budget=1e-4)
    while p.passes_done < 1:
        p.step()
    r.reset()
    p.step()
    assert p.passes_done == 0
    p.finish_pass()
    assert np.all(r.read_sum()[..., 3] == r.samples)


def test_the_samples_rate_is_the_last_passes_not_the_last_bands():
    """The viewer's Msamples/s (Progressive.samples_per_second) is over the launches of the last
    whole image's worth of samples: bands of sky rows render many times as fast as the scene's,
    and the last band's speed alone read 1.6-17 Msamples/s where the device drew 3."""
    from types import SimpleNamespace
    done = cl.command_execution_status.COMPLETE
    renderer = SimpleNamespace(width=10, height=10, resets=0)
    p = Progressive(renderer, budget=1.0)

    clock = [0]                 # the device's, in ns

    def launch(rows, seconds):
        """A finished launch of `rows` taking `seconds` on the device."""
        first = SimpleNamespace(profile=SimpleNamespace(start=clock[0], end=0), command_execution_status=done)
        clock[0] += int(seconds * 1e9)
        last = SimpleNamespace(profile=SimpleNamespace(start=0, end=clock[0]), command_execution_status=done)
        p._queued.append((first, last, rows, 1, 0))
    assert p.samples_per_second == 0.0
    for _ in range(3):          # passes of a cheap band (sky) and a dear one, 10 times its time
        launch((0, 5), 0.001)
        launch((5, 10), 0.010)
        p._collect()
    assert p.passes_done == 3 and p.samples_per_second == pytest.approx(100 / 0.011)
    assert 1 / p.seconds_per_pixel == pytest.approx(50 / 0.010)      # the last band's, for sizing launches
