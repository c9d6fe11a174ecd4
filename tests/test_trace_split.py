"""app/bench/trace_split.py and kernels/trace_split.cl: the rays that the trace split times are the
megakernel's own, and a scene its kernels cannot walk is refused in one line."""

from pathlib import Path

import numpy as np
import pytest

import pathtrace.scene.instances as instancing
from pathtrace.errors import UserError
from pathtrace.scene import load_scene
from pathtrace.bench.trace_split import trace_split
from pathtrace.bench.traversal_stats import traversal_stats
from tests.test_instances import instanced_scene

pytestmark = pytest.mark.specialised     # what the scenes' own programs trace

SCENES = Path(__file__).parent / "scenes"


@pytest.mark.parametrize("name", ["materials", "cornell-box"])
def test_the_rays_recorded_are_the_megakernels_own(backend, name):
    """record_rays draws the megakernel's random numbers in its order and keeps its rules at the
    first vertex (no light sample at a delta BSDF, none where the BSDF is zero or the normals
    disagree; no bounce where sampling fails), so that it writes exactly the rays that the
    megakernel's depth-2 paths trace for the same sample, counted by app/bench/traversal_stats.py:
    over the metals, glass and plastics of `materials` and the quads of `cornell-box`."""
    scene = load_scene(name)
    split = trace_split(backend, scene, 32, 24, 2)
    stats = traversal_stats(backend, scene.with_settings(max_depth=2, nee=True, russian_roulette="off"), 32, 24, 1)
    rays = split.rays_per_pixel
    assert rays["camera"] == 1.0 and 0 < rays["bounce"] < 1 and 0 < rays["shadow"] < 1
    assert round(sum(rays.values()) * 32 * 24) == round(stats.rays_per_sample * 32 * 24)
    assert split.megakernel_ms > 0 and split.record_ms > 0 and all(t > 0 for t in split.trace_ms.values())


def test_a_two_level_scene_is_refused_in_one_line(backend, monkeypatch):
    monkeypatch.setattr(instancing, "FLATTEN_MAX", -1)
    with pytest.raises(UserError, match="two-level BVH"):
        trace_split(backend, instanced_scene(np.random.default_rng(1)), 16, 16, 2)


def test_a_scene_with_media_is_refused_in_one_line(backend):
    """The megakernel's paths there sample free flights and transmittance, which the recorded
    rays would leave out: a split of other work."""
    with pytest.raises(UserError, match="participating media"):
        trace_split(backend, load_scene(str(SCENES / "media-fog.xml")), 16, 16, 2)
