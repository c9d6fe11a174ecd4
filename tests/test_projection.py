"""pbrt-v4's projection light (app/lights/projection.py, kernels/lights/projection.cl): a floor lit
by one against the closed form of its frustum and image; a constant image against a hard-edged
rectangular spot of the same intensity, drawn by hand; and the pbrt-v4 reader's placement (the
CTM) and `power`. It is in the light conformance suite by its examples."""

import math

import numpy as np
import pytest

from pathtrace.errors import UserError
from pathtrace.scene.toml_reader import read_scene_dict
from tests.image_lights import floor_directions, pbrt_light_turned_down, write_image
from tests.test_lights import H, RHO, assert_within_noise, floor_under

BALL = [{"center": [0, 0, 0], "radius": 1, "material": {"type": "diffuse", "rho_d": 0.5}}]


def placed(light):
    return read_scene_dict({"spheres": BALL, "lights": [light]}).lights[0]


def closed_form(light, x, z):
    """Each pixel's RHO / pi E over its grid of floor points: E = I(w) cos / r^2, I(w) scale times
    the nearest texel where w, in the light's frame with y turned round, meets the screen."""
    w, r = floor_directions(light, x, z)
    wx, wy, wz = w[..., 0], -w[..., 1], w[..., 2]
    tan = math.tan(math.radians(light.fov) / 2)
    width, height = light.image.size
    half = np.array([width / height, 1.0]) if width > height else np.array([1.0, height / width])
    with np.errstate(divide="ignore", invalid="ignore"):
        sx, sy = wx / (wz * tan), wy / (wz * tan)
    inside = (wz >= 1e-3) & (np.abs(sx) <= half[0]) & (np.abs(sy) <= half[1])
    i = np.clip(((np.nan_to_num(sx) + half[0]) / (2 * half[0]) * width).astype(np.int64), 0, width - 1)
    j = np.clip(((np.nan_to_num(sy) + half[1]) / (2 * half[1]) * height).astype(np.int64), 0, height - 1)
    texel = light.image.linear_values()[j, i, :3] * inside[..., None]
    e = light.scale * texel * (light.position[1] / r ** 3)[..., None]
    return RHO / np.pi * e.mean(axis=(2, 3))


def test_a_projection_light_throws_its_image_on_the_floor(backend, tmp_path):
    texels = np.random.default_rng(4).integers(30, 255, (3, 5, 3))
    light = {"type": "projection", "position": [0.1, H, 0.2], "direction": [0.2, -1, 0.1], "up": [0, 0, -1],
             "fov": 80, "scale": 2.0, "image": write_image(tmp_path / "slide.png", texels)}
    image, x, z, error = floor_under(light, backend)
    expected = closed_form(placed(light), x, z)
    assert np.any(expected == 0) and np.ptp(expected[expected[..., 0] > 0][:, 0]) > 0   # edges and the image show
    assert_within_noise(image, expected, error)


def test_a_constant_image_is_a_rectangular_spot(backend, tmp_path):
    """A white 2:1 image, straight down, up along -z: intensity `scale` inside |x| / h <= 2 tan
    and |z| / h <= tan (tan = tan(fov / 2)), none outside: a spot of rectangular section."""
    light = {"type": "projection", "position": [0, H, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "fov": 60,
             "scale": 3.0, "image": write_image(tmp_path / "white.png", np.full((2, 4, 3), 255))}
    image, x, z, error = floor_under(light, backend)
    tan = math.tan(math.radians(30))
    d2 = H * H + x * x + z * z
    lit = (np.abs(x) <= 2 * tan * H) & (np.abs(z) <= tan * H)
    expected = RHO / np.pi * 3.0 * (lit * H / np.sqrt(d2) / d2).mean(axis=(2, 3))[..., None] * np.ones(3)
    assert expected.min() == 0 and expected.max() > 0
    assert_within_noise(image, expected, error)


def test_pbrt_places_it_by_the_ctm_and_scales_it_to_its_power(tmp_path):
    write_image(tmp_path / "slide.png", np.random.default_rng(2).integers(0, 255, (4, 6, 3)))
    light = pbrt_light_turned_down(tmp_path, 2, 'LightSource "projection" "string filename" "slide.png" '
                                   '"float fov" 45 "float power" 7')
    assert light.fov == 45
    assert math.isclose(light.power(1.0), 7.0, rel_tol=1e-6)      # pbrt-v4: scale power / (A mean(Y cos^3))


@pytest.mark.parametrize("change,problem", [
    ({"fov": 200}, "lights[0].fov: must be at most 180"),
    ({"fov": 0}, "lights[0].fov: must be in (0, 180) degrees"),
    ({"scale": -1}, "lights[0].scale: must be at least 0"),
    ({"image": None}, "lights[0]: missing 'image'"),
])
def test_bad_projection_lights_are_one_line_naming_the_field(tmp_path, change, problem):
    light = {"type": "projection", "position": [0, 1, 0], "image": write_image(tmp_path / "s.png", np.zeros((2, 2, 3))),
             **change}
    with pytest.raises(UserError) as e:
        read_scene_dict({"spheres": BALL, "lights": [{k: v for k, v in light.items() if v is not None}]}, "bad")
    assert problem in str(e.value) and "\n" not in str(e.value)
