"""What the tests of pbrt-v4's image lights (tests/test_goniometric.py, tests/test_projection.py)
share: an image file written from texels, the directions from such a light to the floor points
of tests/test_lights.py's floor_under in the light's own frame, and a pbrt-v4 file's light placed
by its CTM."""

import numpy as np
from PIL import Image as PILImage

from pathtrace.scene import load_scene


def write_image(path, texels) -> str:
    """An 8-bit image file of `texels` (rows, columns, channels); its path."""
    PILImage.fromarray(np.asarray(texels, np.uint8)).save(path)
    return str(path)


def floor_directions(light, x, z):
    """(w, r): the unit directions from the light to the floor points (x, 0, z), in its frame
    (+z along `direction`, +y along `up` made perpendicular, +x = y cross z: app/lights/light.py
    frame_quaternion), as (..., 3) arrays of (x, y, z), and their distances."""
    d = np.stack([x - light.position[0], np.full_like(x, -light.position[1]), z - light.position[2]], axis=-1)
    r = np.linalg.norm(d, axis=-1)
    w = d / r[..., None]
    zl = np.asarray(light.direction, np.float64) / np.linalg.norm(light.direction)
    yl = np.asarray(light.up, np.float64) - np.dot(light.up, zl) * zl
    yl /= np.linalg.norm(yl)
    xl = np.cross(yl, zl)
    return np.stack([w @ xl, w @ yl, w @ zl], axis=-1), r


def pbrt_light_turned_down(folder, height, light_source):
    """The light of a pbrt-v4 file's `light_source` line under `Translate 0 height 0` and
    `Rotate 90 1 0 0`, checked to be placed by that CTM: at (0, height, 0), its +z the world's -y
    and its +y the world's +z."""
    (folder / "scene.pbrt").write_text(
        f'LookAt 0 3 3  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\nAttributeBegin\nTranslate 0 {height} 0\n'
        f'Rotate 90 1 0 0\n{light_source}\nAttributeEnd\nShape "sphere" "float radius" 0.5\n')
    light = load_scene(folder / "scene.pbrt").lights[0]
    assert np.allclose(light.position, [0, height, 0])
    assert np.allclose(light.direction, [0, -1, 0], atol=1e-12) and np.allclose(light.up, [0, 0, 1], atol=1e-12)
    return light
