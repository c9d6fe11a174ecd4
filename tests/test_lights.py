"""Light sampling for next-event estimation: the cone of a sphere, the alias table, and the
environment map's distribution, each against its density."""

import numpy as np
import pytest
from pyopencl import cltypes
from scipy import stats

from pathtrace.scene.environment import LUMINANCE, Environment
from pathtrace.lights import alias_table, build_light_table, emitted_power
from pathtrace.device.types import RENDER_PARAMS
from tests.test_sampling import chi_square

SOURCE = """
kernel void cone(float4 sphere, float4 x, global const float4 *u, global float4 *out)
{
    int i = get_global_id(0);
    float3 d = sample_sphere_cone(sphere, x.xyz, u[i].x, u[i].y);
    out[i] = (float4)(d, pdf_sphere_cone(sphere, x.xyz));
}
kernel void pick_lights(global const Light *lights, int count, global const uint *bin_bits,
                        global const uint *keep_bits, global int *out)
{
    int i = get_global_id(0);
    out[i] = pick_light(lights, count, bin_bits[i], keep_bits[i]);
}
kernel void env_sample(global const float *marginal, global const float *conditional,
                       global const RenderParams *params, global const float4 *u, global float4 *out)
{
    int i = get_global_id(0);
    RenderParams p = params[0];
    float3 d = sample_environment_map(marginal, conditional, &p, u[i].x, u[i].y);
    out[i] = (float4)(d, pdf_environment_map(marginal, conditional, &p, d));
}
kernel void env_lookup(global const float4 *env, global const RenderParams *params, global const float4 *d,
                       global float4 *out)
{
    int i = get_global_id(0);
    RenderParams p = params[0];
    out[i] = (float4)(lookup_environment(env, &p, d[i].xyz), 0.0f);
}
kernel void env_pdf(global const float *marginal, global const float *conditional,
                    global const RenderParams *params, global const float4 *d, global float *out)
{
    int i = get_global_id(0);
    RenderParams p = params[0];
    out[i] = pdf_environment_map(marginal, conditional, &p, d[i].xyz);
}
"""
N = 300_000


def uniforms(seed):
    return np.random.default_rng(seed).random((N, 4), np.float32)


@pytest.mark.parametrize("distance,radius", [(3.0, 1.0), (50.0, 0.1), (1.05, 1.0)])
def test_cone_samples_are_uniform_in_the_subtended_cone(kernels, distance, radius):
    sphere = cltypes.make_float4(0, 0, distance, radius)
    out = np.zeros((N, 4), np.float32)
    kernels(SOURCE)("cone", N, sphere, cltypes.make_float4(0, 0, 0, 0), uniforms(1), out)
    d = out[:, :3].astype(np.float64)
    cos_max = np.sqrt(1 - (radius / distance) ** 2)
    # every direction meets the sphere; the pdf is 1 / solid angle
    assert np.all(d[:, 2] >= cos_max - 1e-6)
    np.testing.assert_allclose(out[:, 3], 1 / (2 * np.pi * (1 - cos_max)), rtol=1e-3)
    # uniform in solid angle: 1 - cos(theta) uniform on [0, 1 - cos_max], phi uniform; 1 - cos
    # from the perpendicular part, sin^2 / (1 + cos), which float32 resolves in narrow cones
    sin2 = d[:, 0] ** 2 + d[:, 1] ** 2
    one_minus_cos = sin2 / (1 + np.sqrt(1 - sin2))
    k = (radius / distance) ** 2 / (1 + cos_max)
    assert stats.kstest(np.clip(one_minus_cos / k, 0, 1), "uniform").pvalue > 1e-3
    assert stats.kstest((np.arctan2(d[:, 1], d[:, 0]) + np.pi) / (2 * np.pi), "uniform").pvalue > 1e-3


def test_alias_table_reproduces_the_weights_exactly():
    w = np.random.default_rng(2).random(1000) ** 4
    keep, alias = alias_table(w)
    prob = keep / len(w)
    np.add.at(prob, alias, (1 - keep) / len(w))
    np.testing.assert_allclose(prob, w / w.sum(), rtol=1e-9, atol=1e-15)


def pick(kernels, lights, bin_bits, keep_bits):
    out = np.zeros(len(bin_bits), np.int32)
    kernels(SOURCE)("pick_lights", len(bin_bits), lights, np.int32(len(lights)),
                    np.ascontiguousarray(bin_bits, np.uint32), np.ascontiguousarray(keep_bits, np.uint32), out)
    return out


def test_kernel_picks_lights_in_proportion_to_power(kernels):
    spheres = np.array([[0, 0, 0, 1], [5, 0, 0, 0.5], [9, 0, 0, 2], [0, 0, 4, 1]], np.float32)
    emission = np.array([[1, 1, 1], [8, 8, 8], [0, 0, 0], [0.5, 2, 0.1]], np.float32)
    power = emitted_power(spheres, np.zeros((0, 3, 3)), emission @ LUMINANCE, np.zeros(0))
    table = build_light_table(power, Environment.constant((0, 0, 0)))
    assert table.count == 3 and table.env_pick == 0.0 and table.pick[2] == 0
    rng = np.random.default_rng(3)
    out = pick(kernels, table.lights, rng.integers(0, 2**32, N, dtype=np.uint64),
               rng.integers(0, 2**32, N, dtype=np.uint64))
    counts = np.bincount(out, minlength=table.count)
    assert chi_square(counts, table.lights["pick"] * N) > 1e-3


def test_every_light_of_many_is_picked_with_the_probability_nee_divides_by(kernels):
    """2^17 lights whose powers span six decades. The kernel's choice depends on two 32-bit hash
    words (the bin and the keep test), each through a monotone comparison, so its exact
    distribution follows from where each bin and each keep test changes its answer: found by
    running the kernel on both sides of every boundary. The probability of every light must then
    equal the table's `pick`, which NEE divides by (the single-float draw it replaces was off by
    up to 2x here, 26 % of the lights by over 10 %)."""
    count = 2 ** 17
    power = 10.0 ** np.random.default_rng(5).uniform(-3, 3, count)
    table = build_light_table(power, Environment.constant((0, 0, 0)))
    lights = table.lights
    assert table.count == count

    # bins: with every keep word kept, the kernel returns its bin; bin i starts at ceil(i 2^32 / count)
    starts = -(-np.arange(count, dtype=np.int64) * 2**32 // count)
    all_kept = lights.copy()
    all_kept["keep"] = 2**32 - 1
    zeros = np.zeros(count, np.int64)
    np.testing.assert_array_equal(pick(kernels, all_kept, starts, zeros), np.arange(count))
    np.testing.assert_array_equal(pick(kernels, all_kept, starts[1:] - 1, zeros[1:]), np.arange(count - 1))
    assert pick(kernels, all_kept, [2**32 - 1], [0])[0] == count - 1
    p_bin = np.diff(np.append(starts, 2**32)).astype(np.float64) / 2**32

    # keep tests: bin i keeps for words below its threshold
    threshold = lights["keep"].astype(np.int64)
    bins = np.flatnonzero((lights["alias"] != np.arange(count)) & (threshold > 0))
    np.testing.assert_array_equal(pick(kernels, lights, starts[bins], threshold[bins]), lights["alias"][bins])
    np.testing.assert_array_equal(pick(kernels, lights, starts[bins], threshold[bins] - 1), bins)
    p_keep = threshold / 2**32

    exact = p_bin * p_keep
    np.add.at(exact, lights["alias"], p_bin * (1 - p_keep))
    relative = np.abs(exact / lights["pick"] - 1)
    assert relative.max() < 1e-4, (relative.max(), np.mean(relative > 0.1))


def test_light_table_holds_spheres_triangles_and_the_environment():
    """One structure for every emitter: power pi Le area (a triangle emits from its front only),
    the environment chosen as often as all other lights together."""
    spheres = np.array([[0, 0, 0, 1]], np.float32)
    triangles = np.array([[[0, 0, 0], [2, 0, 0], [0, 2, 0]], [[0, 0, 0], [1, 0, 0], [0, 1, 0]]], np.float32)
    power = emitted_power(spheres, triangles, [1.0], [1.0, 0.0])     # the luminances of white and black
    np.testing.assert_allclose(power, [np.pi * 4 * np.pi, np.pi * 2.0, 0.0])
    table = build_light_table(power, Environment.constant((1, 1, 1)))
    assert table.count == 3 and table.env_pick == pytest.approx(0.5)
    assert set(table.lights["prim"]) == {0, 1, -1}
    assert table.pick[0] == pytest.approx(0.5 * 4 * np.pi / (4 * np.pi + 2)) and table.pick[2] == 0


def env_params(env):
    p = np.zeros(1, RENDER_PARAMS)
    h, w, _ = env.image.shape
    p["env_width"], p["env_height"] = w, h
    p["env_frame"][0, :, :3] = env.map_from_world()
    p["env_row_scale"], p["env_row_offset"] = env.row_mapping()
    return p


@pytest.fixture(scope="module")
def sunset():
    from pathtrace.resources import resource_dir
    # tilted, so that the densities are of world directions turned into the map's frame
    env = Environment.from_file(resource_dir("assets") / "envmaps" / "venice_sunset_1k.hdr", rotation=75.0,
                                up=tuple(np.array([0.3, 0.8, -0.5]) / np.linalg.norm([0.3, 0.8, -0.5])))
    env.image = env.image[::4, ::4].copy()     # 256 x 128: faster, just as peaked
    return env


def test_environment_pdf_integrates_to_one(kernels, sunset):
    nt, nphi = 1000, 2000
    theta = (np.arange(nt) + 0.5) / nt * np.pi
    phi = (np.arange(nphi) + 0.5) / nphi * 2 * np.pi
    t, f = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(t) * np.sin(f), np.cos(t), -np.sin(t) * np.cos(f), 0 * t], -1).reshape(-1, 4)
    out = np.zeros(len(d), np.float32)
    marginal, conditional = sunset.sampling_cdfs()
    kernels(SOURCE)("env_pdf", len(d), marginal, conditional, env_params(sunset), d.astype(np.float32), out)
    integral = (out.reshape(nt, nphi) * np.sin(t)).sum() * (np.pi / nt) * (2 * np.pi / nphi)
    assert integral == pytest.approx(1.0, abs=5e-3)


def test_environment_samples_follow_their_pdf(kernels, sunset):
    """Histogram of sampled directions over (theta, phi) cells against the pdf integrated over
    each cell; and the brightest part of the map (the sun) gets the most samples."""
    marginal, conditional = sunset.sampling_cdfs()
    out = np.zeros((N, 4), np.float32)
    kernels(SOURCE)("env_sample", N, marginal, conditional, env_params(sunset), uniforms(4), out)
    d = out[:, :3].astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1, atol=1e-5)
    theta = np.arccos(np.clip(d[:, 1], -1, 1))
    phi = np.mod(np.arctan2(d[:, 0], -d[:, 2]), 2 * np.pi)
    nt, nphi, sub = 16, 32, 24
    counts, _, _ = np.histogram2d(theta, phi, [np.linspace(0, np.pi, nt + 1), np.linspace(0, 2 * np.pi, nphi + 1)])
    tt = (np.arange(nt * sub) + 0.5) / (nt * sub) * np.pi
    pp = (np.arange(nphi * sub) + 0.5) / (nphi * sub) * 2 * np.pi
    t, f = np.meshgrid(tt, pp, indexing="ij")
    grid = np.stack([np.sin(t) * np.sin(f), np.cos(t), -np.sin(t) * np.cos(f), 0 * t], -1).reshape(-1, 4)
    pdf = np.zeros(len(grid), np.float32)
    kernels(SOURCE)("env_pdf", len(grid), marginal, conditional, env_params(sunset), grid.astype(np.float32), pdf)
    cell = (np.pi / (nt * sub)) * (2 * np.pi / (nphi * sub))
    expected = (pdf.reshape(nt * sub, nphi * sub) * np.sin(t) * cell).reshape(nt, sub, nphi, sub).sum(axis=(1, 3)) * N
    assert chi_square(counts.ravel(), expected.ravel()) > 1e-3
    # the pdf the sampler reports for its own samples is the density evaluated there
    assert np.all(out[:, 3] > 0)


# -- delta lights: point, spot, directional ------------------------------------------------

RHO, H, SIZE = 0.5, 1.0, 4.0     # the floor's albedo, the light's height, the view's width


def floor_under(light, backend, nee=True, sampler="power"):
    """A diffuse floor of albedo RHO (y = 0) seen straight down by an orthographic camera that
    covers [-2, 2]^2, lit by `light` alone: each pixel's radiance is RHO / pi times the
    irradiance there, closed forms below. Returns the image, 32 x 32 pixels of 256 samples, and
    the floor's x and z at an 8 x 8 grid of points in each pixel (axes 2 and 3), over which the
    closed forms are averaged as the pixel averages its samples; and the standard error of each
    pixel's mean (the samples differ only by where in the pixel they land)."""
    from pathtrace.rendering.renderer import Renderer
    from pathtrace.scene.toml_reader import read_scene_dict
    scene = read_scene_dict({
        "camera": {"type": "orthographic", "eye": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1],
                   "height": SIZE},
        "environment": {"color": 0},
        "render": {"max_depth": 2, "russian_roulette": "off", "nee": nee, "light_sampler": sampler},
        "materials": {"floor": {"type": "diffuse", "rho_d": RHO}},
        "meshes": [{"vertices": [[-9, 0, -9], [9, 0, -9], [9, 0, 9], [-9, 0, 9]], "faces": [[0, 3, 2, 1]],
                    "material": "floor"}],
        "lights": light if isinstance(light, list) else [light]}, "floor")
    r = Renderer(backend, scene, 32, 32)
    r.add_samples(256)
    points = ((np.arange(32 * 8) + 0.5) / (32 * 8) * SIZE - SIZE / 2).reshape(32, 8)
    x = np.broadcast_to(points[None, :, None, :], (32, 32, 8, 8))
    z = np.broadcast_to(points[:, None, :, None], (32, 32, 8, 8))
    return r.mean(), x, z, np.sqrt(r.variance() / r.samples)


def assert_within_noise(image, expected, error):
    """Each pixel within 5 standard errors of the closed form (and float32's rounding): with
    1024 pixels and 3 channels a false alarm is a chance of 2e-3."""
    assert np.all(np.abs(image - expected) <= 5 * error + 1e-5 * np.abs(expected) + 1e-7), \
        np.max(np.abs(image - expected) / (error + 1e-12))


def test_a_point_light_gives_the_inverse_square_law(backend):
    image, x, z, error = floor_under({"type": "point", "position": [0, H, 0], "intensity": [3, 2, 1]}, backend)
    d2 = H * H + x * x + z * z
    expected = RHO / np.pi * np.array([3, 2, 1]) * (H / np.sqrt(d2) / d2).mean(axis=(2, 3))[..., None]
    assert_within_noise(image, expected, error)


@pytest.mark.parametrize("falloff", ["linear", "smoothstep"])
def test_a_spot_light_falls_off_between_its_beam_and_its_cutoff(backend, falloff):
    image, x, z, error = floor_under({"type": "spot", "position": [0, H, 0], "look_at": [0, 0, 0], "intensity": 2.0,
                               "cutoff_angle": 40.0, "beam_width": 25.0, "falloff": falloff}, backend)
    d2 = H * H + x * x + z * z
    theta = np.degrees(np.arctan(np.hypot(x, z) / H))
    if falloff == "linear":        # Mitsuba 3's: linear in the angle
        profile = np.clip((40.0 - theta) / 15.0, 0, 1)
    else:                          # pbrt-v4's: a smoothstep in the cosine
        t = np.clip((np.cos(np.radians(theta)) - np.cos(np.radians(40))) /
                    (np.cos(np.radians(25)) - np.cos(np.radians(40))), 0, 1)
        profile = t * t * (3 - 2 * t)
    expected = (RHO / np.pi * 2.0 * profile * H / np.sqrt(d2) / d2).mean(axis=(2, 3))
    assert_within_noise(image[..., 1], expected, error[..., 1])
    theta = theta.mean(axis=(2, 3))
    assert image[..., 1][theta > 42].max() == 0 and image[..., 1][theta < 24].min() > 0


@pytest.mark.parametrize("sampler", ["power", "tree"])
def test_a_hard_edged_spot_lights_its_cone_through_either_light_sampler(backend, sampler):
    """beam_width = cutoff_angle: full intensity inside, none outside. The light tree once bounded
    it by theta_e = 0, and its importance test (cos theta' <= cos theta_e, pbrt-v4's) then
    refused every point: a black floor (review 2026-11-28, F4). A second spot, the same but
    pointing up (it lights nothing seen), makes the tree a tree; choosing by power it takes half
    the light samples, the tree none."""
    spot = {"type": "spot", "position": [0, H, 0], "look_at": [0, 0, 0], "intensity": 2.0, "cutoff_angle": 30.0,
            "beam_width": 30.0}
    image, x, z, error = floor_under([spot, {**spot, "look_at": [0, 2 * H, 0]}], backend, sampler=sampler)
    d2 = H * H + x * x + z * z
    inside = np.degrees(np.arctan(np.hypot(x, z) / H)) < 30.0
    expected = (RHO / np.pi * 2.0 * inside * H / np.sqrt(d2) / d2).mean(axis=(2, 3))
    # the pixels the edge crosses left out: 8 x 8 points do not integrate a step to within noise
    whole = inside.all(axis=(2, 3)) | ~inside.any(axis=(2, 3))
    assert_within_noise(image[..., 1][whole], expected[whole], error[..., 1][whole])
    assert image[..., 1][inside.all(axis=(2, 3))].min() > 0


def test_a_directional_light_gives_its_irradiance_times_the_cosine(backend):
    direction = np.array([1.0, -2.0, 0.5])
    image, _, _, _ = floor_under({"type": "directional", "direction": direction.tolist(), "irradiance": 3.0}, backend)
    cos = 2.0 / np.linalg.norm(direction)
    np.testing.assert_allclose(image, RHO / np.pi * 3.0 * cos, rtol=1e-5)


def test_delta_lights_join_the_table_by_power():
    from pathtrace.lights import DirectionalLight, PointLight, SpotLight
    point = PointLight([0, 1, 0], [1.0, 1.0, 1.0])
    spot = SpotLight([0, 1, 0], [0, -1, 0], [2.0, 2.0, 2.0], 30.0, 30.0)
    sun = DirectionalLight([0, -1, 0], [1.0, 1.0, 1.0])
    for light in (point, spot, sun):
        light.check()
    power = np.array([np.pi * 2.0])          # one emissive primitive of power 2 pi
    table = build_light_table(power, Environment.constant((0, 0, 0)), [point, spot, sun], radius=2.0)
    expected = np.array([2 * np.pi, 4 * np.pi, 2 * 2 * np.pi * (1 - np.cos(np.radians(30))), np.pi * 4])
    np.testing.assert_allclose(table.lights["pick"], expected / expected.sum(), rtol=1e-6)
    assert table.types == ("point", "spot", "directional")
    assert list(table.lights["prim"]) == [0, -1, -1, -1] and table.pick[0] == table.lights["pick"][0]


@pytest.mark.parametrize("light,problem", [
    ({"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": 1, "cutoff_angle": -5},
     "lights[0].cutoff_angle: must be in (0, 180] degrees"),
    ({"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": 1, "cutoff_angle": 200},
     "lights[0].cutoff_angle: must be in (0, 180] degrees"),
    ({"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": 1, "cutoff_angle": 20,
      "beam_width": 30}, "lights[0].beam_width: must be in [0, cutoff_angle = 20] degrees"),
    ({"type": "spot", "position": [0, 1, 0], "direction": [0, 0, 0], "intensity": 1}, "lights[0].direction: must not be zero"),
    ({"type": "directional", "direction": [0, 0, 0], "irradiance": 1}, "lights[0].direction: must not be zero"),
    ({"type": "point", "position": [0, 1, 0], "intensity": -1}, "lights[0].intensity: must be non-negative"),
    ({"type": "point", "position": [0, 1, 0], "intensity": 1e30}, "lights[0].intensity: must be three numbers in [0, 1e20]"),
    ({"type": "point", "intensity": 1}, "lights[0]: missing 'position'"),
    ({"type": "lamp", "position": [0, 1, 0]}, "lights[0].type: must be one of point, spot, directional"),
    ({"type": ["point"], "position": [0, 1, 0]}, "lights[0].type: must be one of point, spot, directional"),
    ({"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": 1, "falloff": "cubic"},
     "lights[0].falloff: must be linear or smoothstep")])
def test_bad_lights_are_one_line_naming_the_field(light, problem):
    from pathtrace.errors import UserError
    from pathtrace.scene.toml_reader import read_scene_dict
    with pytest.raises(UserError) as e:
        read_scene_dict({"spheres": [{"center": [0, 0, 0], "radius": 1, "material": {"type": "diffuse", "rho_d": 0.5}}],
                         "lights": [light]}, "bad")
    assert problem in str(e.value) and "\n" not in str(e.value)


# -- the light tree ------------------------------------------------------------------------

def lamp_field(n=20_000, size=60.0, seed=5):
    """n small emissive triangles facing down, 1 to 1.5 above a diffuse floor, spread over
    size x size, their radiance over three decades; the camera, below them, sees the floor
    only: many lights, lit from out of view, most of them far from any one point."""
    from pathtrace.cameras import PerspectiveCamera
    from pathtrace.materials.table import pack
    from pathtrace.scene.description import Mesh, SceneBuilder, diffuse
    rng = np.random.default_rng(seed)
    b = SceneBuilder()
    h = size * 0.7
    floor = np.array([[-h, 0, -h], [-h, 0, h], [h, 0, h], [h, 0, -h]], np.float32)
    b.add_mesh(Mesh("floor", floor, np.array([[0, 1, 2], [0, 2, 3]], np.int32), None, b.material(diffuse(0.5))))
    centres = np.column_stack([rng.uniform(-size / 2, size / 2, n), rng.uniform(1.0, 1.5, n),
                               rng.uniform(-size / 2, size / 2, n)])
    lamps = (centres[:, None, :] + np.array([[-0.08, 0, -0.08], [0.08, 0, -0.08], [0, 0, 0.08]])).astype(np.float32)
    radiance = 10.0 ** rng.uniform(-1, 2, (n, 1)) * rng.uniform(0.3, 1, (n, 3))
    rows = b.materials.add_rows(pack("black", {}, emission=radiance))
    one = np.array([[0, 1, 2]], np.int32)
    for k in range(n):
        b.add_mesh(Mesh(f"lamp {k}", lamps[k], one, None, int(rows[k])))
    return b.build("lamp-field", camera=PerspectiveCamera([0, 0.6, 0], [0, 0, -1], [0, 1, 0], 40.0),
                   environment=Environment.constant((0, 0, 0)))


TREE_SOURCE = """
kernel void tree_picks(SCENE_KERNEL_ARGS, int num_spheres, float4 x, float4 n, global int *out)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    int i = get_global_id(0);
    Rng rng = make_rng(i, 1, 2, 3);
    float pick = 1.0f;
    out[i] = pick_from_tree(&sc, &sc.lights[0], x.xyz, n.xyz, &rng, &pick);
}
kernel void tree_probabilities(SCENE_KERNEL_ARGS, int num_spheres, float4 x, float4 n, int first,
                               global float *out)
{
    SceneData sc = SCENE_DATA(num_spheres, 0);
    int i = get_global_id(0);
    out[i] = tree_pick_probability(&sc, sc.lights[first + i].alias, x.xyz, n.xyz);
}
"""


def test_the_light_tree_picks_each_light_with_the_probability_nee_divides_by(kernels):
    """At a point of the floor, the tree's walks land on each light as often as the probability
    recomputed from its leaf says (which MIS divides by), those probabilities sum to 1, and a
    light behind the point's surface is never picked."""
    from pyopencl import cltypes
    from pathtrace.compiler.compiled import CompiledScene
    from tests.conftest import scene_arrays
    scene = lamp_field(n=400, size=8.0).with_settings(light_sampler="tree")
    c = CompiledScene(scene)
    from pathtrace.lights import LIGHTS
    assert c.lights.tree and c.lights.count == 1 and c.lights.lights["type"][0] == len(LIGHTS)   # its root
    run = kernels(TREE_SOURCE, c.features(scene.settings, scene.camera))
    x, n = cltypes.make_float4(0.3, 0.0, -1.0, 0), cltypes.make_float4(0, 1, 0, 0)
    lights = len(c.lights.lights) - c.lights.count
    p = np.zeros(lights, np.float32)
    run("tree_probabilities", lights, *scene_arrays(c), np.int32(c.num_spheres), x, n, np.int32(c.lights.count), p)
    assert p.sum() == pytest.approx(1.0, abs=1e-5) and p.max() < 0.5
    picks = np.zeros(N, np.int32)
    run("tree_picks", N, *scene_arrays(c), np.int32(c.num_spheres), x, n, picks)
    assert picks.min() >= c.lights.count
    counts = np.bincount(picks - c.lights.count, minlength=lights)
    assert chi_square(counts, p.astype(np.float64) * N) > 1e-3
    # from below the floor, facing down, no lamp is above the surface's side
    below = np.zeros(64, np.int32)
    run("tree_picks", 64, *scene_arrays(c), np.int32(c.num_spheres), cltypes.make_float4(0, 2.0, 0, 0),
        cltypes.make_float4(0, 1, 0, 0), below)
    assert np.all(below == -1)


def test_the_light_tree_lowers_the_variance_of_many_lights_and_keeps_the_mean(backend):
    """20,000 lamps over three decades of power, out of view: at equal samples the tree's
    per-pixel variance (median over pixels) is at least 3x lower than the choice by power
    (measured 4.2x, 2026-11-24, PoCL), and its image has the mean of the estimator without NEE,
    pixel by pixel (a Z-test, pooled over 4x4 blocks)."""
    from pathtrace.rendering.renderer import Renderer
    from tests.stats import z_test
    scene = lamp_field().with_settings(max_depth=2, russian_roulette="off")
    images = {}
    for sampler, nee, spp in (("power", True, 64), ("tree", True, 64), ("tree", False, 1024)):
        r = Renderer(backend, scene.with_settings(light_sampler=sampler, nee=nee), 48, 32)
        assert r.lights.tree == (sampler == "tree")
        r.add_samples(spp)
        images[sampler, nee] = (r.mean(), r.variance(), r.samples)
    ratio = np.median(images["power", True][1]) / np.median(images["tree", True][1])
    assert ratio >= 3.0, ratio
    (tree, var_tree, n_tree), (plain, var_plain, n_plain) = images["tree", True], images["tree", False]
    ok, p, threshold = z_test(tree, var_tree / n_tree, plain, var_plain / n_plain, block=4)
    assert ok, f"smallest p-value {p:.3g} below the Sidak threshold {threshold:.3g}"


@pytest.mark.parametrize("rows", ["centres", "poles"])
def test_a_maps_rows_lie_where_its_convention_puts_them(kernels, rows):
    """A map whose every row holds its row's number, looked up down a meridian: pathtrace's rows
    (and pbrt-v4's lat-long lookups) are texel centres, (r + 1/2) / H of the way from the zenith;
    Mitsuba 3's envmap puts its first row at the zenith and its last at the nadir, r / (H - 1) of
    the way (src/emitters/envmap.cpp: uv * (res - 1)), which its envmaps take (`rows = "poles"`).
    A helper's render of a 32-row gradient beside Mitsuba 3's differed by up to half a row."""
    h, w = 5, 4
    image = np.repeat(np.arange(h, dtype=np.float32)[:, None, None], w, 1).repeat(3, 2)
    env = Environment(image, rows=rows)
    theta = np.linspace(0.0, np.pi, 41)
    d = np.stack([np.sin(theta), np.cos(theta), 0 * theta, 0 * theta], -1).astype(np.float32)
    out = np.zeros((len(d), 4), np.float32)
    flat = np.concatenate([image, np.zeros((h, w, 1), np.float32)], -1).reshape(-1, 4)
    params = env_params(env)
    params["env_scale"] = 1.0
    kernels(SOURCE)("env_lookup", len(d), flat, params, d, out)
    row = theta / np.pi * (h - 1) if rows == "poles" else np.clip(theta / np.pi * h - 0.5, 0, h - 1)
    np.testing.assert_allclose(out[:, 0], row, atol=2e-5)


@pytest.mark.parametrize("up,rotation", [((0, 1, 0), 0.0), ((0, 1, 0), 75.0), ((0, 0, 1), 0.0), ((0, 0, 1), 30.0),
                                         ((0.3, 0.8, -0.5), 200.0), ((0, -1, 0), 10.0), ((1e-7, -1, 0), 10.0),
                                         ((1, 0, 0), 90.0)])
def test_a_maps_zenith_lies_up_and_its_centre_column_where_its_rotation_turns_it(kernels, up, rotation):
    """The map's top row is seen looking `up`, its bottom row looking away from it, and its centre
    column (u = 1/2, the map's own -z) in the direction a turn of `rotation` degrees about the
    zenith and then the shortest turn from +y to up give it (Environment.up, rotation;
    world_from_map): a map of 8 rows whose texels hold their row and column, looked up in those
    directions through the kernel."""
    from pathtrace.scene.environment import world_from_map
    h, w = 8, 16
    rows, cols = np.meshgrid(np.arange(h, dtype=np.float32), np.arange(w, dtype=np.float32), indexing="ij")
    image = np.stack([rows, cols, np.zeros_like(rows)], -1)
    up = tuple(np.array(up, float) / np.linalg.norm(up))
    env = Environment(image, rotation=rotation, up=up)
    place = world_from_map(up, rotation)
    assert np.allclose(place @ [0, 1, 0], up) and np.allclose(place.T @ place, np.eye(3))
    # the centre column at the horizon, a quarter turn either side, the zenith, the nadir
    towards = [place @ v for v in ([0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0])]
    d = np.array([[*v, 0] for v in towards], np.float32)
    out = np.zeros((len(d), 4), np.float32)
    params = env_params(env)
    params["env_scale"] = 1.0
    flat = np.concatenate([image, np.zeros((h, w, 1), np.float32)], -1).reshape(-1, 4)
    kernels(SOURCE)("env_lookup", len(d), flat, params, d, out)
    # u = 1/2 + atan2(x, -z) / 2 pi in the map's frame: column u w - 1/2; rows (v h - 1/2), clamped
    np.testing.assert_allclose(out[:3, 0], h / 2 - 0.5, atol=1e-4)
    np.testing.assert_allclose(out[:3, 1], [w / 2 - 0.5, 3 * w / 4 - 0.5, w / 4 - 0.5], atol=1e-3)
    np.testing.assert_allclose(out[3:, 0], [0, h - 1], atol=1e-4)


def test_a_mirrored_map_shows_at_one_side_what_it_shows_unmirrored_at_the_other(kernels):
    """`mirrored` swaps the map's left and right about its centre column before it is turned: looked
    up towards +x it gives the column the unmirrored map gives towards -x, and along -z the same
    centre column. Mitsuba 3's envmap whose to_world mirrors (`<scale x="-1"/>`) is placed so: its
    placement is to_world times Mitsuba's half turn, an orthogonal matrix of determinant -1
    (rendered beside Mitsuba 3.9.1: the sky's blocks within 0.1 %)."""
    from pathtrace.scene.environment import world_from_map
    h, w = 4, 16
    image = np.repeat(np.arange(w, dtype=np.float32)[None, :, None], h, 0).repeat(3, 2)
    flat = np.concatenate([image, np.zeros((h, w, 1), np.float32)], -1).reshape(-1, 4)
    d = np.array([[1, 0, 0], [-1, 0, 0], [0, 0, -1]], np.float64)     # in the turned map's frame
    looked = {}
    for mirrored in (False, True):
        params = env_params(Environment(image, rotation=25.0, mirrored=mirrored))
        params["env_scale"] = 1.0
        out = np.zeros((3, 4), np.float32)
        towards = np.column_stack([d[:, :3] @ world_from_map((0, 1, 0), 25.0).T, np.zeros(3)]).astype(np.float32)
        kernels(SOURCE)("env_lookup", 3, flat, params, towards, out)
        looked[mirrored] = out[:, 0]
    np.testing.assert_allclose(looked[True], looked[False][[1, 0, 2]], atol=1e-3)
    up, rotation, mirrored = Environment.mitsuba_orientation(np.diag([-1.0, 1.0, 1.0, 1.0]), "x", pytest.fail)
    assert mirrored and np.allclose(world_from_map(up, rotation, mirrored), np.diag([1.0, 1.0, -1.0]))


ENVIRONMENT_ALONE = {
    "toml": '[camera]\neye = [0, 0, 0]\nlook_at = [0, 0, 1]\n[environment]\ncolor = [0.2, 0.4, 0.8]\n'
            '[render]\nwidth = 12\nheight = 8\n',
    "xml": '<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="12"/>'
           '<integer name="height" value="8"/></film></sensor>'
           '<emitter type="constant"><rgb name="radiance" value="0.2, 0.4, 0.8"/></emitter></scene>',
    "pbrt": 'Film "rgb" "integer xresolution" 12 "integer yresolution" 8\nCamera "perspective"\nWorldBegin\n'
            'LightSource "infinite" "rgb L" [0.2 0.4 0.8]\n',
}


@pytest.mark.parametrize("integrator", ["path", "bdpt"])
@pytest.mark.parametrize("suffix", sorted(ENVIRONMENT_ALONE))
def test_a_scene_of_its_environment_alone_renders_it(tmp_path, capsys, suffix, integrator):
    """A file with an environment and no shapes renders the environment, as Mitsuba 3 and pbrt-v4
    render such a file (the readers refused it; the tree of no primitives is a root of four empty
    slots, app/compiler/bvh.py), with one line saying there are no shapes: every pixel of a
    constant sky is its radiance. A TOML file with neither shapes nor an [environment] (an empty
    one, a truncated one) is refused rather than drawn as the default white sky."""
    import pathtrace
    path = tmp_path / f"sky.{suffix}"
    path.write_text(ENVIRONMENT_ALONE[suffix])
    scene = pathtrace.load(str(path))
    err = capsys.readouterr().err
    assert err.count("the scene has no shapes; pathtrace renders its environment alone") == 1, err
    assert len(scene.spheres) == len(scene.meshes) == len(scene.shapes) == 0
    image = pathtrace.render(scene, spp=2, integrator=integrator)
    assert image.shape == (8, 12, 3)
    assert np.allclose(image, [0.2, 0.4, 0.8], rtol=1e-5), (image.min(axis=(0, 1)), image.max(axis=(0, 1)))
    if suffix == "toml":
        from pathtrace.errors import UserError
        path.write_text("")
        with pytest.raises(UserError, match="no \\[\\[spheres\\]\\].* and no \\[environment\\]: nothing to render"):
            pathtrace.load(str(path))
