"""What the tests of the names a format's renderer knows and pathtrace does not read share
(tests/test_pbrt_parameter_names.py, tests/test_mitsuba_parameter_names.py): such a name is
warned of, and the scene still renders."""

import numpy as np

from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene


def warnings_of_a_scene_that_renders(path, capsys, backend) -> list:
    """The lines a scene file's reading wrote to stderr, the scene checked to render (8x8, one
    sample per pixel) to finite pixels, some lit."""
    scene = load_scene(str(path))
    lines = capsys.readouterr().err.splitlines()
    r = Renderer(backend, scene, 8, 8)
    r.add_samples(1)
    r.finish()
    assert np.all(np.isfinite(r.mean())) and r.mean().max() > 0
    return lines
