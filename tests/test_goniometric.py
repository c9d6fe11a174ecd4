"""pbrt-v4's goniometric light (app/lights/goniometric.py, kernels/lights/goniometric.cl): a floor
lit by one against the closed form of its equal-area map, computed on the host with
app/scene/pbrt/equal_area.py's mapping; a constant map against the point light it then is; and
the pbrt-v4 reader's placement (the CTM) and `power`. It is in the light conformance suite by its
examples."""

import math

import numpy as np
import pytest

from pathtrace.errors import UserError
from pathtrace.lights.light import luminance
from pathtrace.scene.pbrt.equal_area import sphere_to_square
from pathtrace.scene.toml_reader import read_scene_dict
from tests.image_lights import floor_directions, pbrt_light_turned_down, write_image
from tests.test_lights import H, RHO, assert_within_noise, floor_under


def closed_form(light, x, z):
    """Each pixel's RHO / pi E, E = I(w) cos / r^2 over the pixel's grid of floor points, I(w) the
    nearest texel of the light's grey map at the equal-area square of w in the light's space
    (y and z swapped)."""
    w, r = floor_directions(light, x, z)
    local = w[..., [0, 2, 1]]     # (x, z, y): the map's pole is +y
    texels = light.map.params["image"].texels[..., 0]
    n = texels.shape[0]
    uv = sphere_to_square(local.reshape(-1, 3))
    i = np.minimum((uv * n).astype(np.int64), n - 1)
    value = texels[i[:, 1], i[:, 0]].reshape(r.shape)
    e = value * light.position[1] / r ** 3
    return RHO / np.pi * np.asarray(light.intensity) * e.mean(axis=(2, 3))[..., None]


def test_a_goniometric_light_lights_the_floor_as_its_map_says(backend, tmp_path):
    rng = np.random.default_rng(3)
    texels = rng.integers(20, 255, (8, 8, 3))
    light = {"type": "goniometric", "position": [0.2, H, -0.1], "intensity": [3, 2, 1], "up": [0.3, -1, 0.4],
             "direction": [1, 0, 0], "image": write_image(tmp_path / "map.png", texels)}
    image, x, z, error = floor_under(light, backend)
    placed = read_scene_dict({"spheres": [{"center": [0, 0, 0], "radius": 1, "material": {"type": "diffuse",
                                                                                           "rho_d": 0.5}}],
                              "lights": [light]}).lights[0]
    expected = closed_form(placed, x, z)
    assert expected.max() > 0 and np.ptp(expected[..., 0]) > 0.2 * expected[..., 0].max()   # the map shows
    assert_within_noise(image, expected, error)


def test_a_constant_map_is_a_point_light_of_its_value(backend, tmp_path):
    """A map of one grey g: the point light of intensity g I (pbrt-v4's image is linear here: an
    8-bit PNG decodes from sRGB, 128 to 0.2158)."""
    g = ((128 / 255 + 0.055) / 1.055) ** 2.4
    light = {"type": "goniometric", "position": [0, H, 0], "intensity": [3, 2, 1], "up": [1, 0, 0],
             "image": write_image(tmp_path / "grey.png", np.full((4, 4, 3), 128))}
    image, x, z, error = floor_under(light, backend)
    d2 = H * H + x * x + z * z
    expected = RHO / np.pi * g * np.array([3, 2, 1]) * (H / np.sqrt(d2) / d2).mean(axis=(2, 3))[..., None]
    assert_within_noise(image, expected, error)


def test_pbrt_places_it_by_the_ctm_and_scales_it_to_its_power(tmp_path):
    write_image(tmp_path / "map.png", np.random.default_rng(1).integers(0, 255, (8, 8, 3)))
    # Rotate 90 about x: the light's +z is the world's -y, its +y (the map's pole) the world's +z
    light = pbrt_light_turned_down(tmp_path, 1, 'LightSource "goniometric" "string filename" "map.png" "rgb I" '
                                   '[1 1 1] "float power" 10')
    # pbrt-v4: I scale power / k_e, k_e = 4 pi mean(map): the power is `power` times I's luminance
    assert math.isclose(light.power(1.0), 10 * luminance(np.ones(3)), rel_tol=1e-6)


@pytest.mark.parametrize("change,problem", [
    ({"image": "missing.png"}, "lights[0].image"),
    ({"image": None}, "lights[0]: missing 'image'"),
    ({"up": [0, 0, 2]}, "lights[0].up: must not be parallel to direction"),
])
def test_bad_goniometric_lights_are_one_line_naming_the_field(tmp_path, change, problem):
    light = {"type": "goniometric", "position": [0, 1, 0], "intensity": 1,
             "image": write_image(tmp_path / "map.png", np.zeros((2, 2, 3))), **change}
    light = {k: v for k, v in light.items() if v is not None}
    with pytest.raises(UserError) as e:
        read_scene_dict({"spheres": [{"center": [0, 0, 0], "radius": 1, "material": {"type": "diffuse",
                                                                                       "rho_d": 0.5}}],
                         "lights": [light]}, "bad")
    assert problem in str(e.value) and "\n" not in str(e.value)


def test_a_map_that_is_not_square_is_refused(tmp_path):
    light = {"type": "goniometric", "position": [0, 1, 0], "intensity": 1,
             "image": write_image(tmp_path / "wide.png", np.zeros((2, 4, 3)))}
    with pytest.raises(UserError, match=r"lights\[0\]\.image: an equal-area map is square, got 4x2"):
        read_scene_dict({"spheres": [{"center": [0, 0, 0], "radius": 1, "material": {"type": "diffuse",
                                                                                       "rho_d": 0.5}}],
                         "lights": [light]}, "bad")
