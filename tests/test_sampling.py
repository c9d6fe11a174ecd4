"""The direction warps of kernels/sampling.cl against their densities (chi-square tests)."""

import numpy as np
import pytest
from scipy import stats

from pathtrace.device.opencl import BUILD_OPTIONS
from pathtrace.resources import resource_dir
from tests.conftest import KernelRunner

SOURCE = """
kernel void warp(int which, float exponent, global const float4 *u, global float4 *out)
{
    int i = get_global_id(0);
    float3 d = which == 0 ? sample_cosine_hemisphere(u[i].x, u[i].y)
                          : sample_cosine_power(u[i].x, u[i].y, exponent);
    out[i] = (float4)(d, 0.0f);
}
kernel void frame(global const float4 *n, global float4 *t, global float4 *b)
{
    int i = get_global_id(0);
    float3 tt, bb;
    make_frame(n[i].xyz, &tt, &bb);
    t[i] = (float4)(tt, 0.0f); b[i] = (float4)(bb, 0.0f);
}
"""
N = 400_000


def draw(kernels, which, exponent=1.0, seed=0):
    u = np.random.default_rng(seed).random((N, 4), np.float32)
    out = np.zeros((N, 4), np.float32)
    kernels(SOURCE)("warp", N, np.int32(which), np.float32(exponent), u, out)
    return out[:, :3].astype(np.float64)


def chi_square(counts, expected):
    keep = expected > 5           # pool sparse bins, as usual for the test
    obs = np.append(counts[keep], counts[~keep].sum())
    exp = np.append(expected[keep], expected[~keep].sum())
    if exp[-1] == 0:
        obs, exp = obs[:-1], exp[:-1]
    return stats.chisquare(obs, exp * obs.sum() / exp.sum()).pvalue


def test_directions_are_unit_and_in_the_upper_hemisphere(kernels):
    for which, e in ((0, 1.0), (1, 1000.0)):
        d = draw(kernels, which, e)
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-5)
        assert d[:, 2].min() >= 0.0


def test_cosine_hemisphere_matches_its_pdf(kernels):
    """pdf cos(theta)/pi: the probability of a bin z in [z0, z1], phi in [p0, p1] is
    (z1^2 - z0^2)(p1 - p0) / (2 pi)."""
    d = draw(kernels, 0)
    z_edges, p_edges = np.linspace(0, 1, 21), np.linspace(-np.pi, np.pi, 17)
    counts, _, _ = np.histogram2d(d[:, 2], np.arctan2(d[:, 1], d[:, 0]), [z_edges, p_edges])
    expected = np.outer(np.diff(z_edges ** 2), np.diff(p_edges)) / (2 * np.pi) * N
    assert chi_square(counts.ravel(), expected.ravel()) > 1e-3


@pytest.mark.parametrize("exponent", [1.0, 10.0, 100.0, 1000.0])
def test_cosine_power_matches_its_pdf(kernels, exponent):
    """pdf (n+1)/(2 pi) cos^n: a bin's probability is (z1^(n+1) - z0^(n+1))(p1 - p0)/(2 pi)."""
    d = draw(kernels, 1, exponent, seed=int(exponent))
    # equal-probability bins in z: z = q^(1/(n+1)) for quantiles q
    z_edges = np.linspace(0, 1, 21) ** (1 / (exponent + 1))
    p_edges = np.linspace(-np.pi, np.pi, 17)
    counts, _, _ = np.histogram2d(d[:, 2], np.arctan2(d[:, 1], d[:, 0]), [z_edges, p_edges])
    expected = np.outer(np.diff(z_edges ** (exponent + 1)), np.diff(p_edges)) / (2 * np.pi) * N
    assert chi_square(counts.ravel(), expected.ravel()) > 1e-3


def test_frame_is_orthonormal_for_every_normal(kernels):
    rng = np.random.default_rng(4)
    n = rng.normal(size=(10000, 3))
    n[:4] = [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1e-8, -1]]
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n4 = np.column_stack([n, np.zeros(len(n))]).astype(np.float32)
    t, b = np.zeros_like(n4), np.zeros_like(n4)
    kernels(SOURCE)("frame", len(n), n4, t, b)
    t, b = t[:, :3], b[:, :3]
    for x, y in ((t, b), (t, n), (b, n)):
        assert np.abs(np.sum(x * y, axis=1)).max() < 1e-5
    np.testing.assert_allclose(np.linalg.norm(t, axis=1), 1, atol=1e-5)
    np.testing.assert_allclose(np.cross(t, b), n, atol=1e-5)   # right-handed


CIRCLE = """
kernel void circle(global const float *t, global float2 *out)
{
    int i = get_global_id(0);
    out[i] = (float2)(COS_TURNS(t[i]), SIN_TURNS(t[i]));
}
"""


@pytest.mark.parametrize("cpu_form", [True, False], ids=["cospi", "cos"])
def test_turns_give_cosine_and_sine(backend, cpu_form):
    """COS_TURNS(t), SIN_TURNS(t) = cos 2 pi t, sin 2 pi t in both of their forms (CPU_DEVICE:
    cospi and sinpi, else cos and sin), for the turns the samplers pass: [0, 1), the concentric disk's
    [-1/8, 3/8] and the environment's shifted by its rotation. The cospi form is exact at
    quarter turns."""
    source = (resource_dir("kernels") / "sampling.cl").read_text() + CIRCLE
    options = list(BUILD_OPTIONS) + (["-DCPU_DEVICE"] if cpu_form else [])
    quarters = np.arange(-8, 13, dtype=np.float32) / 4
    t = np.concatenate([quarters, np.random.default_rng(3).uniform(-2.5, 3.0, 100_000)]).astype(np.float32)
    out = np.zeros((t.size, 2), np.float32)
    KernelRunner(backend, source, options=options)("circle", t.size, t, out)
    angle = 2 * np.pi * t.astype(np.float64)
    np.testing.assert_allclose(out, np.stack([np.cos(angle), np.sin(angle)], axis=1), rtol=0, atol=2e-6)
    if cpu_form:
        exact = np.round(np.stack([np.cos(angle[:quarters.size]), np.sin(angle[:quarters.size])], axis=1))
        assert np.array_equal(out[:quarters.size], exact)      # -0 == 0
