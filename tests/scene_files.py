"""The scene files the tests render as they are, and an image's mean with its standard error:
tests/scenes' Mitsuba and pbrt-v4 files, the assets' TOML scenes and the pbrt-v4 references'
scenes, for the invariants that hold on every scene (tests/test_nee.py: NEE against paths alone;
tests/test_bdpt.py: BDPT against the path tracer)."""

from pathlib import Path

import numpy as np

from pathtrace.rendering.renderer import Renderer

ROOT = Path(__file__).resolve().parent.parent
SCENE_FILES = sorted([*(ROOT / "tests" / "scenes").glob("*.xml"), *(ROOT / "tests" / "scenes").glob("*.pbrt"),
                      *(ROOT / "assets" / "scenes").glob("*.toml"), *(ROOT / "tests" / "references" / "pbrt-v4").glob("*.pbrt")])
SCENE_SIZE = (16, 12)


def image_mean(backend, scene, spp):
    """The image's mean per channel at SCENE_SIZE and its standard error, from the pixels'
    sample variances."""
    r = Renderer(backend, scene, *SCENE_SIZE)
    r.add_samples(spp)
    r.finish()
    assert r.dropped_samples() == 0
    pixels = SCENE_SIZE[0] * SCENE_SIZE[1]
    return r.mean().mean(axis=(0, 1)), np.sqrt(r.variance().sum(axis=(0, 1)) / r.samples) / pixels
