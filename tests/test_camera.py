"""The cameras of kernels/cameras/ (pinhole, thin lens, orthographic) and the pixel filters of
kernels/filters/ (box, tent, gaussian): their rays' geometry, and their samples against their
densities (chi-square tests)."""

import math
import re

import numpy as np
import pytest
from scipy import integrate

from pathtrace.cameras import KERNELS as CAMERA_KERNELS, Camera, OrthographicCamera, PerspectiveCamera, ThinLensCamera
from pathtrace.cameras.registry import toml_names
from pathtrace.device.features import GENERIC, Features
from pathtrace.filters import FILTERS, PixelFilter
from pathtrace.device.types import RENDER_PARAMS
from tests.commands import in_process
from tests.test_sampling import chi_square

SOURCE = """
kernel void rays(const RenderParams p, global const float4 *film, global float4 *o, global float4 *d)
{
    int i = get_global_id(0);
    CameraRay ray = generate_ray(&p, film[i].x, film[i].y, film[i].zw);
    o[i] = (float4)(ray.o, 0.0f);
    d[i] = (float4)(ray.d, 0.0f);
}
kernel void disk(global const float4 *u, global float2 *out)
{
    int i = get_global_id(0);
    out[i] = sample_concentric_disk(u[i].xy);
}
kernel void offsets(const RenderParams p, global float2 *out)
{
    int i = get_global_id(0);
    Rng rng = make_rng(i, 7, 3, 11);
    float4 u = next_uniform4(&rng);
    out[i] = sample_filter(&p, u.xy, &rng);
}
"""
N = 300_000
W, H = 64, 48
# every camera and filter in one program, chosen at run time from RenderParams as the generic
# program chooses them (a build where there was one per kind); the scenes' own programs, with
# one camera and filter compiled in, are the renders' (tests/test_reference.py, test_bdpt.py)
FEATURES = Features(camera=GENERIC, filter=GENERIC)


def params(camera, pixel_filter=PixelFilter()):
    p = np.zeros((), RENDER_PARAMS)
    camera.pack(p, W / H)
    p["filter"] = pixel_filter.params()
    # the generic program's choices, as the renderer packs them (Renderer.params)
    p["camera_type"] = CAMERA_KERNELS.index(camera.kernel)
    p["filter_type"] = FILTERS.index(pixel_filter.name)
    p["width"], p["height"] = W, H
    return p


def rays(kernels, camera, film):
    o, d = np.zeros((len(film), 4), np.float32), np.zeros((len(film), 4), np.float32)
    kernels(SOURCE, FEATURES)("rays", len(film), params(camera), np.ascontiguousarray(film, np.float32), o, d)
    return o[:, :3].astype(np.float64), d[:, :3].astype(np.float64)


def test_concentric_disk_samples_are_uniform(kernels):
    u = np.random.default_rng(1).random((N, 4), np.float32)
    out = np.zeros((N, 2), np.float32)
    kernels(SOURCE, FEATURES)("disk", N, u, out)
    r2 = (out.astype(np.float64) ** 2).sum(axis=1)
    assert r2.max() <= 1 + 1e-6
    # uniform on the disk: r^2 and the angle uniform and independent, 16 x 16 cells of equal area
    phi = np.mod(np.arctan2(out[:, 1], out[:, 0]), 2 * np.pi)
    counts, _, _ = np.histogram2d(r2, phi, [np.linspace(0, 1, 17), np.linspace(0, 2 * np.pi, 17)])
    assert chi_square(counts.ravel(), np.full(256, N / 256)) > 1e-3


def test_a_thin_lens_focuses_every_lens_point_on_the_plane_in_focus(kernels):
    camera = ThinLensCamera([1.0, 2.0, 6.0], [0.0, 0.5, 0.0], [0, 1, 0], 40.0, aperture_radius=0.3, focus_distance=4.0)
    forward = camera.basis(W / H)[0]
    rng = np.random.default_rng(2)
    n = 2000
    film = np.column_stack([np.repeat([[10.5, 7.25], [40.0, 30.0]], n // 2, axis=0), rng.random((n, 2))])
    o, d = rays(kernels, camera, film)
    # origins on the aperture: the disk of radius 0.3 about the eye, across the view direction
    offset = o - camera.eye
    assert np.abs(offset @ forward).max() < 1e-5
    assert np.linalg.norm(offset, axis=1).max() <= 0.3 + 1e-5
    assert np.linalg.norm(offset, axis=1).mean() == pytest.approx(0.2, abs=0.01)   # 2/3 of the radius
    # every ray of one film point meets the plane in focus at the pinhole ray's point there
    pinhole = camera.as_type("perspective")
    _, d0 = rays(kernels, pinhole, film)
    t = (4.0 - offset @ forward) / (d @ forward)
    hits = o + t[:, None] * d
    expected = camera.eye + d0 * (4.0 / (d0 @ forward))[:, None]
    np.testing.assert_allclose(hits, expected, atol=2e-5)


def test_an_orthographic_camera_sends_parallel_rays_from_a_rectangle(kernels):
    camera = OrthographicCamera([0.0, 3.0, 0.0], [0.0, 0.0, 0.0], [0, 0, -1], height=4.0)
    film = np.array([[0, 0, 0.5, 0.5], [W, H, 0.5, 0.5], [W / 2, H / 2, 0.1, 0.9], [W, 0, 0.5, 0.5]])
    o, d = rays(kernels, camera, film)
    np.testing.assert_allclose(d, np.tile([0, -1, 0], (4, 1)), atol=1e-6)
    # the view is 4 high and 4 W/H wide; right is +x, up is -z
    half_w = 2.0 * W / H
    np.testing.assert_allclose(o, [[-half_w, 3, -2], [half_w, 3, 2], [0, 3, 0], [half_w, 3, -2]], atol=1e-5)


def filter_weight(f: PixelFilter, x):
    r = f.radius
    if f.name == "box":
        return np.where(np.abs(x) <= r, 1.0, 0.0)
    if f.name == "tent":
        return np.maximum(0.0, 1 - np.abs(x) / r)
    g = lambda x: np.exp(-x * x / (2 * f.stddev ** 2))   # noqa: E731
    return np.where(np.abs(x) <= r, np.maximum(0.0, g(x) - g(r)), 0.0)


@pytest.mark.parametrize("pixel_filter", [
    PixelFilter("box"), PixelFilter("box", 1.5), PixelFilter("tent"), PixelFilter("tent", 2.0),
    PixelFilter("gaussian"), PixelFilter("gaussian", 1.5), PixelFilter("gaussian", 0.5, 1.0)],
    ids=lambda f: f"{f.name}-{f.radius:g}-{f.stddev:g}")
def test_filter_samples_follow_the_filter(kernels, pixel_filter):
    """Filter importance sampling: offsets distributed as the filter's weights (pbrt-v4 section
    8.8), over a 16 x 16 grid of cells covering its support; the gaussian's second case is a
    radius below two stddev, sampled from uniform candidates."""
    out = np.zeros((N, 2), np.float32)
    camera = PerspectiveCamera()
    kernels(SOURCE, FEATURES)("offsets", N, params(camera, pixel_filter), out)
    r = pixel_filter.radius
    assert np.abs(out).max() <= r * (1 + 1e-6)
    edges = np.linspace(-r, r, 17)
    mass = np.array([integrate.quad(lambda x: float(filter_weight(pixel_filter, x)), a, b)[0]
                     for a, b in zip(edges[:-1], edges[1:])])
    mass /= mass.sum()
    counts, _, _ = np.histogram2d(out[:, 0], out[:, 1], [edges, edges])
    assert chi_square(counts.ravel(), np.outer(mass, mass).ravel() * N) > 1e-3
    assert chi_square(counts.sum(axis=1), mass * N) > 1e-3


@pytest.mark.parametrize("bad,problem", [
    (dict(name="cone"), "type: must be box, tent or gaussian"),
    (dict(name="tent", radius=0.0), "radius: must be in [0.001, 32]"),
    (dict(name="box", radius=1e30), "radius: must be in [0.001, 32]"),
    (dict(name="gaussian", stddev=-1.0), "stddev: must be in [0.001, 32]"),
    (dict(name="gaussian", stddev=math.nan), "stddev: must be in [0.001, 32]"),
    (dict(name="gaussian", stddev=1e-40), "stddev: must be in [0.001, 32]")])
def test_filters_refuse_what_they_cannot_be(bad, problem):
    with pytest.raises(ValueError, match=re.escape(problem)):
        PixelFilter(**bad).check()


def test_the_filter_types_are_the_command_lines_in_its_order():
    """The command line refuses a filter without loading the declarations (rendering/choices.py);
    RenderParams.filter_type is an index into the one order."""
    from pathtrace.filters import TYPES
    assert tuple(TYPES) == FILTERS


SPHERE = {"center": [0, 0, 0], "radius": 1, "material": {"type": "diffuse", "rho_d": 0.5}}


@pytest.mark.parametrize("camera,problem", [
    ({"aperture_radius": 0.1}, "camera: a thinlens camera needs 'focus_distance'"),
    ({"type": "thinlens", "aperture_radius": 0.1}, "camera: a thinlens camera needs 'focus_distance'"),
    ({"type": "thinlens"}, "camera: a thinlens camera needs 'focus_distance'"),
    ({"aperture_radius": -0.1, "focus_distance": 2}, "camera.aperture_radius: must be in [0, 1e+30]"),
    ({"aperture_radius": 0.1, "focus_distance": 0}, "camera.focus_distance: must be in (0, 1e+30]"),
    ({"type": "orthographic", "height": 1e31}, "camera.height: must be in (0, 1e+30]"),
    ({"type": "orthographic", "vfov": 30}, "camera.vfov: an orthographic camera has no vfov"),
    ({"type": "fisheye"}, f"camera.type: must be one of {', '.join(toml_names())}, got 'fisheye'"),
    ({"type": ["perspective"]}, f"camera.type: must be one of {', '.join(toml_names())}, got ['perspective']")])
def test_bad_cameras_are_one_line_naming_the_field(camera, problem):
    from pathtrace.errors import UserError
    from pathtrace.scene.toml_reader import read_scene_dict
    with pytest.raises(UserError) as e:
        read_scene_dict({"camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0], **camera}, "spheres": [SPHERE]}, "bad")
    assert problem in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize("pixel_filter,problem", [
    ("cone", "render.filter.type: must be one of box, tent, gaussian"),
    ({"type": "tent", "radius": 0}, "render.filter.radius: must be in [0.001, 32] pixels"),
    ({"type": "box", "radius": 1e30}, "render.filter.radius: must be in [0.001, 32] pixels"),
    ({"type": "box", "stddev": 1}, "render.filter.stddev: a box filter has no stddev")])
def test_bad_filters_are_one_line_naming_the_field(pixel_filter, problem):
    from pathtrace.errors import UserError
    from pathtrace.scene.toml_reader import read_scene_dict
    with pytest.raises(UserError) as e:
        read_scene_dict({"render": {"filter": pixel_filter}, "spheres": [SPHERE]}, "bad")
    assert problem in str(e.value) and "\n" not in str(e.value)


def test_the_command_line_filter_overrides_the_scenes(tmp_path):
    """--filter NAME[:RADIUS[:STDDEV]]; a bad one is one line and exit 2 (a usage error)."""
    scene = tmp_path / "s.toml"
    scene.write_text('[render]\nfilter = "box"\n[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\n'
                     'material = { type = "emitter", Le = 1 }\n[[lights]]\ntype = "point"\nposition = [0, 3, 0]\n'
                     'intensity = 1\n')
    from pathtrace.cli.main import build_parser
    from pathtrace.cli.options import apply_render_options
    from pathtrace.scene import load_scene
    args = build_parser().parse_args(["render", str(scene), "-o", "x.png", "--filter", "gaussian:1.5:0.25"])
    assert apply_render_options(load_scene(str(scene)), args).settings.filter == PixelFilter("gaussian", 1.5, 0.25)
    run = in_process("render", scene, "--filter", "tent:0", "-o", tmp_path / "x.png")
    assert run.returncode == 2 and "radius: must be in [0.001, 32] pixels" in run.stderr
    run = in_process("render", scene, "--no-nee", "--size", "8x8", "--spp", "1", "-q", "-o", tmp_path / "x.png")
    assert run.returncode == 0 and "without it (--no-nee) they light nothing" in run.stderr


@pytest.mark.parametrize("mirrored", [False, True])
def test_fly_controls_move_and_turn_towards_the_images_right(mirrored):
    """D strafes, and a mouse move to the right turns the view, towards the side of the image
    that is on the right: -(forward x up) for a mirrored camera."""
    from pathtrace.viewer.controls import FlyControls
    camera = PerspectiveCamera((0, 0, 5), (0, 0, 0), (0, 1, 0), mirrored=mirrored)
    image_right = camera.basis(1.0)[1]
    controls = FlyControls(held={"D"})
    before = camera.eye.copy()
    assert controls.update(camera, 0.1)
    assert np.dot(camera.eye - before, image_right) > 0
    turned = PerspectiveCamera((0, 0, 5), (0, 0, 0), (0, 1, 0), mirrored=mirrored)
    FlyControls().update(turned, 0.0, look_dx=20)
    assert np.dot(turned.look_at - turned.eye, image_right) > 0


def test_a_camera_refuses_the_fields_of_other_types_and_changes_type_keeping_its_frame():
    camera = PerspectiveCamera([0.0, 1.0, 5.0], [0.0, 0.5, 0.0], [0, 1, 0], 30.0, mirrored=True)
    with pytest.raises(AttributeError, match="a perspective camera has no 'aperture'"):
        camera.aperture = 0.3
    with pytest.raises(TypeError, match="Camera is the cameras' base"):
        Camera()
    lens = camera.as_type("thinlens", aperture_radius=0.3, focus_distance=4.0)
    assert (type(lens), lens.vfov, lens.aperture_radius, lens.mirrored, lens.kernel) == (ThinLensCamera, 30.0, 0.3, True, "thinlens")
    np.testing.assert_array_equal(lens.eye, camera.eye)
    assert lens.as_type("thinlens", aperture_radius=0.0).kernel == "perspective"   # a pinhole compiles as one


def test_a_camera_type_maps_the_values_a_format_gives_by_its_declarations():
    """Camera.from_file, on what app/parameters.py's read gives of a type's parameters and
    format_only (FILM and TO_WORLD the reader's): pbrt-v4's perspective with a lens is a thin
    lens, its fov on the shorter axis; Mitsuba's fov on x of a 2:1 film, and its orthographic
    view two to_world units across the film's width; a bad value names the format's parameter."""
    from pathtrace.cameras.camera import FILM, TO_WORLD, frame_of
    from pathtrace.parameters import read

    def camera(cls, fmt, file, to_world=np.eye(4)):
        given = {FILM: (200, 100), TO_WORLD: to_world}
        values = read(cls.parameters + cls.format_only, fmt, lambda p, name: file.get(name), given)
        return cls.from_file(fmt, values, given, frame_of(to_world, x_right=fmt == "pbrt"), None)
    lens = camera(PerspectiveCamera, "pbrt", {"fov": 60.0, "lensradius": 0.5, "focaldistance": 3.0})
    assert (type(lens), lens.vfov, lens.aperture_radius, lens.focus_distance) == \
        (ThinLensCamera, pytest.approx(60.0), 0.5, 3.0)
    assert camera(PerspectiveCamera, "pbrt", {}).vfov == pytest.approx(90.0)      # pbrt-v4's default, no lens
    wide = camera(PerspectiveCamera, "mitsuba", {"fov": 90.0})
    assert wide.vfov == pytest.approx(math.degrees(2 * math.atan(0.5)))
    assert camera(OrthographicCamera, "mitsuba", {}, np.diag([2.0, 2.0, 2.0, 1.0])).height == pytest.approx(2.0)
    with pytest.raises(ValueError, match=r"^screenwindow: takes x0 x1 y0 y1"):
        camera(PerspectiveCamera, "pbrt", {"screenwindow": [0.0, 1.0, 0.0]})
    with pytest.raises(ValueError, match=r"^fov_axis: must be x, y, diagonal, smaller or larger, got 'z'"):
        camera(PerspectiveCamera, "mitsuba", {"fov": 30.0, "fov_axis": "z"})
