"""The spherical camera (app/cameras/spherical.py, pbrt-v4's `spherical`): its rays against
pbrt-v4's mapping formulas (src/pbrt/cameras.cpp, SphericalCamera::GenerateRay, and
src/pbrt/util/math.cpp, EqualAreaSquareToSphere and WrapEqualAreaSquare, written out here) for a
camera read from a pbrt file; a closed form (inside a uniformly emitting sphere every direction
sees its radiance); an environment map's texels where their directions lie; and the one-line
refusals."""

import math
from dataclasses import replace

import numpy as np
import pytest

from pathtrace.cameras import CAMERAS
from pathtrace.scene.environment import Environment
from pathtrace.errors import UserError
from pathtrace.materials.table import Material
from pathtrace.scene import RenderSettings, SceneBuilder
from tests.test_camera import H, W, rays
from tests.test_integrator import render
from tests.test_pbrt import fails, scene

FILM = [(0.5, 0.5), (16.0, 24.0), (32.3, 12.7), (63.9, 47.2), (48.0, 6.1), (5.0, 40.0),
        (-0.4, 10.0), (64.3, 30.0), (20.0, -0.3), (40.0, 48.4)]      # the last four past the edges


def pbrt_direction(mapping, u, v):
    """pbrt-v4's direction for film point (u, v) in [0, 1]^2 before its y/z swap."""
    if mapping == "equirectangular":
        theta, phi = math.pi * v, 2 * math.pi * u
        return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
    if u < 0:
        u, v = -u, 1 - v
    elif u > 1:
        u, v = 2 - u, 1 - v
    if v < 0:
        u, v = 1 - u, -v
    elif v > 1:
        u, v = 1 - u, 2 - v
    u, v = 2 * u - 1, 2 * v - 1
    signed = 1 - (abs(u) + abs(v))
    r = 1 - abs(signed)
    phi = (1.0 if r == 0 else (abs(v) - abs(u)) / r + 1) * math.pi / 4
    s = r * math.sqrt(max(0.0, 2 - r * r))
    return np.array([math.copysign(math.cos(phi), u) * s, math.copysign(math.sin(phi), v) * s,
                     math.copysign(1 - r * r, signed)])


@pytest.mark.parametrize("mapping", ["equirectangular", "equalarea"])
def test_rays_follow_pbrts_mapping_through_its_lookat(kernels, tmp_path, mapping):
    eye, look, up = np.array([1.0, 2.0, 3.0]), np.array([2.0, 2.5, -4.0]), np.array([0.3, 1.0, 0.0])
    camera = scene(tmp_path, "Shape \"sphere\" \"float radius\" 0.1\n",
                   f'LookAt {" ".join(map(str, [*eye, *look, *up]))}\nCamera "spherical" "string mapping" "{mapping}"\n'
                   f'Film "rgb" "integer xresolution" {W} "integer yresolution" {H}').camera
    assert (camera.type, camera.mapping) == ("spherical", mapping)
    # pbrt-v4's LookAt: camera space +z along dir, +x = up x dir, +y = dir x x
    d = (look - eye) / np.linalg.norm(look - eye)
    x = np.cross(up / np.linalg.norm(up), d)
    x /= np.linalg.norm(x)
    y = np.cross(d, x)
    film = np.array([[sx, sy, 0.5, 0.5] for sx, sy in FILM])
    o, got = rays(kernels, camera, film)
    for (sx, sy), g in zip(FILM, got):
        m = pbrt_direction(mapping, sx / W, sy / H)
        expected = m[0] * x + m[2] * y + m[1] * d          # pbrt swaps y and z: +z is up in the mapping
        np.testing.assert_allclose(g, expected, atol=2e-5, err_msg=f"film point {(sx, sy)}")
    np.testing.assert_allclose(o, np.tile(eye, (len(FILM), 1)), atol=1e-6)
    # the viewer's picking ray (Camera.ray) is the kernel's at the same point
    for (sx, sy), g in list(zip(FILM, got))[:6]:
        np.testing.assert_allclose(camera.ray(W / H, 2 * sx / W - 1, 1 - 2 * sy / H)[1], g, atol=2e-5)


def world(camera, width, height, environment=None, inside=None):
    b = SceneBuilder()
    if inside is not None:
        b.add_sphere(*inside)
    else:
        b.add_sphere((0, -100, 0), 1e-3, Material("black"))    # a speck: a scene has a primitive
    return b.build("spherical", camera=camera, **({"environment": environment} if environment else {}),
                   settings=RenderSettings(width=width, height=height, max_depth=1, russian_roulette="off"))


@pytest.mark.parametrize("mapping", ["equirectangular", "equalarea"])
def test_inside_a_uniformly_emitting_sphere_every_pixel_sees_its_radiance(backend, mapping):
    """Closed form: from any point inside a sphere emitting Le inwards, every direction sees Le,
    so the whole image is Le, poles, seams and corners included."""
    le = np.array([0.7, 1.3, 2.0])
    lamp = Material("black", emission=le, emits_back=True)
    camera = CAMERAS["spherical"]([0.3, -0.2, 0.4], [1.0, 0.0, 0.4], [0, 1, 0], mapping=mapping)
    mean, _, _ = render(backend, world(camera, 32, 16, inside=((0, 0, 0), 2.0, lamp)), 8)
    np.testing.assert_allclose(mean, np.broadcast_to(le, mean.shape), rtol=1e-5)


def test_an_environment_map_is_seen_texel_for_texel(backend):
    """A map of 8 x 8 texel blocks of random colours, seen through an equirectangular camera at
    the origin whose frame lines its mapping up with the map's (kernels/environment.cl: u = 1/2 +
    atan2(x, -z) / 2 pi, v = acos(y) / pi): right along +z, looking down -x, up +y, mirrored (as
    pbrt's LookAt is). Each pixel inside a block shows the block's colour exactly, whatever the
    filter's jitter: the map at the pixel's directions."""
    rng = np.random.default_rng(4)
    blocks = rng.uniform(0.1, 2.0, (4, 8, 3))
    image = np.repeat(np.repeat(blocks, 8, axis=0), 8, axis=1).astype(np.float32)      # 32 x 64
    camera = CAMERAS["spherical"]([0, 0, 0], [-1, 0, 0], [0, 1, 0], mirrored=True, mapping="equirectangular")
    np.testing.assert_allclose(camera.frame()[1], [0, 0, 1], atol=1e-12)
    mean, _, _ = render(backend, world(camera, 64, 32, environment=Environment(image)), 8)
    inner = np.zeros((32, 64), bool)
    for a in range(1, 7):
        inner[:, np.arange(64) % 8 == a] = True
    inner[np.arange(32) % 8 == 0] = inner[np.arange(32) % 8 == 7] = False
    assert inner.sum() == 32 * 64 * 36 // 64
    np.testing.assert_allclose(mean[inner], image[inner], rtol=1e-4)


def test_bad_mappings_and_other_formats_are_one_line(tmp_path):
    assert "'mapping': must be equalarea or equirectangular, got 'fisheye'" in fails(
        tmp_path, 'Camera "spherical" "string mapping" "fisheye"\nWorldBegin\nShape "sphere"\n')
    from pathtrace.scene.toml_reader import read_scene_dict
    with pytest.raises(UserError, match=r"camera\.mapping: must be equalarea or equirectangular, got 'x'"):
        read_scene_dict({"camera": {"type": "spherical", "eye": [0, 0, 0], "look_at": [0, 0, 1], "mapping": "x"},
                         "spheres": [{"center": [0, 0, 3], "radius": 1, "material": {"type": "diffuse", "rho_d": 0.5}}]},
                        "bad")
    with pytest.raises(UserError, match=r"camera\.vfov: a spherical camera has no vfov"):
        read_scene_dict({"camera": {"type": "spherical", "eye": [0, 0, 0], "look_at": [0, 0, 1], "vfov": 40},
                         "spheres": [{"center": [0, 0, 3], "radius": 1, "material": {"type": "diffuse", "rho_d": 0.5}}]},
                        "bad")
    assert replace(CAMERAS["spherical"](), mapping="equirectangular").lens()[0] == 1.0
