"""Light sampling for next-event estimation: the cone of a sphere, the alias table, and the
environment map's distribution, each against its density."""

import numpy as np
import pytest
from pyopencl import cltypes
from scipy import stats

from pathtrace.environment import Environment
from pathtrace.lights import alias_table, build_light_table, emitted_power
from pathtrace.types import RENDER_PARAMS
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
    power = emitted_power(spheres, np.zeros((0, 3, 3)), emission, np.zeros((0, 3)))
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
    power = emitted_power(spheres, triangles, np.array([[1.0, 1, 1]]), np.array([[1.0, 1, 1], [0, 0, 0]]))
    np.testing.assert_allclose(power, [np.pi * 4 * np.pi, np.pi * 2.0, 0.0])
    table = build_light_table(power, Environment.constant((1, 1, 1)))
    assert table.count == 3 and table.env_pick == pytest.approx(0.5)
    assert set(table.lights["prim"]) == {0, 1, -1}
    assert table.pick[0] == pytest.approx(0.5 * 4 * np.pi / (4 * np.pi + 2)) and table.pick[2] == 0


def env_params(env):
    p = np.zeros(1, RENDER_PARAMS)
    h, w, _ = env.image.shape
    p["env_width"], p["env_height"], p["env_rotation"] = w, h, env.rotation / 360.0
    return p


@pytest.fixture(scope="module")
def sunset():
    from pathtrace.resources import resource_dir
    env = Environment.from_file(resource_dir("assets") / "envmaps" / "venice_sunset_1k.hdr", rotation=75.0)
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
