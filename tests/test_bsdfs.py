"""The BSDFs of kernels/bsdfs/ through the dispatch of kernels/bsdf.cl: sampling against the pdf,
the pdf's normalisation, energy conservation, and the sample weight against eval cos / pdf."""

import numpy as np
import pytest
from pyopencl import cltypes

from pathtrace.materials import pack
from tests.test_sampling import chi_square

SOURCE = """
kernel void bsdf_sample(global const Material *mat, float4 wo, global const float4 *u,
                        global float4 *wi, global float4 *weight)
{
    int i = get_global_id(0);
    BSDFSample s;
    int ok = sample_bsdf(mat, wo.xyz, u[i].xyz, &s);
    wi[i] = (float4)(s.wi, ok ? s.pdf : 0.0f);
    /* w: 0 no direction, 1 a non-delta lobe, 2 a delta lobe */
    weight[i] = ok ? (float4)(s.weight, (s.lobe & LOBE_DELTA) ? 2.0f : 1.0f) : (float4)(0.0f);
}
kernel void bsdf_eval(global const Material *mat, float4 wo, global const float4 *wi,
                      global float4 *out)
{
    int i = get_global_id(0);
    out[i] = (float4)(eval_bsdf(mat, wo.xyz, wi[i].xyz), pdf_bsdf(mat, wo.xyz, wi[i].xyz));
}
"""
def direction(theta_deg, phi_deg=0.0):
    """The outgoing direction at theta degrees from the normal (and phi from the tangent), as a
    kernel argument."""
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return cltypes.make_float4(np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t), 0)


def material(rho_d, rho_s, n):
    return pack("phong", {"rho_d": rho_d, "rho_s": rho_s, "n": n})


def sample(kernels, m, wo, count=400_000, seed=0):
    """Directions (with the pdf sample() reported in w) and weights (w: 0 where no direction
    resulted, 1 for a non-delta lobe, 2 for a delta one)."""
    u = np.random.default_rng(seed).random((count, 4), np.float32)
    wi, weight = np.zeros((count, 4), np.float32), np.zeros((count, 4), np.float32)
    kernels(SOURCE)("bsdf_sample", count, m, wo, u, wi, weight)
    return wi.astype(np.float64), weight


def evaluate(kernels, m, wo, wi):
    wi4 = np.column_stack([wi[:, :3], np.zeros(len(wi))]).astype(np.float32)
    out = np.zeros((len(wi), 4), np.float32)
    kernels(SOURCE)("bsdf_eval", len(wi), m, wo, wi4, out)
    return out[:, :3].astype(np.float64), out[:, 3].astype(np.float64)


def hemisphere_grid(nz=1500, nphi=1500):
    """Midpoints of an (z, phi) grid over the upper hemisphere; each cell has solid angle dz dphi."""
    z = (np.arange(nz) + 0.5) / nz
    phi = (np.arange(nphi) + 0.5) / nphi * 2 * np.pi - np.pi
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    s = np.sqrt(1 - zz ** 2)
    return np.stack([s * np.cos(pp), s * np.sin(pp), zz], -1).reshape(-1, 3), (1 / nz) * (2 * np.pi / nphi)


@pytest.mark.parametrize("rho_d,rho_s,n", [(0.5, 0.5, 1.0), (0.3, 0.6, 20.0), (0.0, 1.0, 50.0), (1.0, 0.0, 1.0)])
def test_pdf_integrates_to_one_at_normal_incidence(kernels, rho_d, rho_s, n):
    grid, cell = hemisphere_grid()
    _, pdf = evaluate(kernels, material(rho_d, rho_s, n), direction(0), grid)
    assert pdf.sum() * cell == pytest.approx(1.0, abs=2e-3)


@pytest.mark.parametrize("theta", [0, 35, 70])
@pytest.mark.parametrize("rho_d,rho_s,n", [(0.3, 0.6, 20.0), (0.1, 0.9, 200.0)])
def test_sampled_directions_follow_the_pdf(kernels, theta, rho_d, rho_s, n):
    """Every draw yields a direction or (glossy, below the surface) ends the path; the yielded
    directions' histogram matches the pdf integrated over each bin."""
    m, wo = material(rho_d, rho_s, n), direction(theta)
    wi, weight = sample(kernels, m, wo, seed=theta)
    ok = weight[:, 3] > 0
    assert np.all(wi[ok, 2] > 0)
    # bins in (z, phi) around the normal; the pdf integrated over each on a fine grid
    nz, nphi = 16, 16
    grid, cell = hemisphere_grid(nz * 60, nphi * 60)
    _, pdf = evaluate(kernels, m, wo, grid)
    expected = (pdf * cell).reshape(nz, 60, nphi, 60).sum(axis=(1, 3)) * len(wi)
    counts, _, _ = np.histogram2d(wi[ok, 2], np.arctan2(wi[ok, 1], wi[ok, 0]),
                                  [np.linspace(0, 1, nz + 1), np.linspace(-np.pi, np.pi, nphi + 1)])
    assert expected.sum() == pytest.approx(ok.sum(), rel=0.01)   # the mass below the surface
    assert chi_square(counts.ravel(), expected.ravel()) > 1e-3


@pytest.mark.parametrize("theta", [0, 45, 80])
@pytest.mark.parametrize("rho_d,rho_s,n", [(0.8, 0.2, 1.0), (0.5, 0.5, 10.0), (0.0, 1.0, 100.0),
                                           ((0.9, 0.1, 0.2), (0.1, 0.9, 0.3), 30.0)])
def test_albedo_is_at_most_one_and_the_estimator_finds_it(kernels, theta, rho_d, rho_s, n):
    """Directional albedo = integral of f cos over the hemisphere, by quadrature; it is at most
    1 (energy conservation), and the mean sample weight is an unbiased estimate of it."""
    m, wo = material(rho_d, rho_s, n), direction(theta)
    grid, cell = hemisphere_grid(3000, 1500)
    f, _ = evaluate(kernels, m, wo, grid)
    albedo = (f * grid[:, 2:3]).sum(axis=0) * cell
    assert np.all(albedo <= 1.0 + 2e-3)
    wi, weight = sample(kernels, m, wo, seed=theta)
    mean = weight[:, :3].mean(axis=0)
    err = weight[:, :3].std(axis=0) / np.sqrt(len(weight))
    assert np.all(np.abs(mean - albedo) < 5 * err + 2e-3), (mean, albedo)


@pytest.mark.parametrize("rho_d,rho_s,n", [(0.3, 0.6, 20.0), ((0.9, 0.1, 0.2), (0.1, 0.9, 0.3), 30.0)])
def test_sample_weights_carry_f_cos_into_every_region(kernels, rho_d, rho_s, n):
    """For a lobe-mixture the one-sample weight is f_lobe cos / (P_lobe pdf_lobe), not eval cos
    / pdf sample by sample; but over any region of directions, the sum of the weights of the
    samples that land there, over the number drawn, estimates the integral of f cos over it.
    Tested per (z, phi) bin against quadrature, with each bin's standard error."""
    m, wo = material(rho_d, rho_s, n), direction(40)
    count = 400_000
    wi, weight = sample(kernels, m, wo, count=count, seed=7)
    ok = weight[:, 3] > 0
    nz, nphi, sub = 8, 8, 100
    edges = [np.linspace(0, 1, nz + 1), np.linspace(-np.pi, np.pi, nphi + 1)]
    where = (wi[ok, 2], np.arctan2(wi[ok, 1], wi[ok, 0]))
    grid, cell = hemisphere_grid(nz * sub, nphi * sub)
    f, _ = evaluate(kernels, m, wo, grid)
    for c in range(3):
        expected = (f[:, c] * grid[:, 2] * cell).reshape(nz, sub, nphi, sub).sum(axis=(1, 3))
        w = weight[ok, c].astype(np.float64)
        total, _, _ = np.histogram2d(*where, edges, weights=w)
        total_sq, _, _ = np.histogram2d(*where, edges, weights=w * w)
        mean = total / count
        se = np.sqrt(np.maximum(total_sq / count - mean ** 2, 0) / count)
        assert np.all(np.abs(mean - expected) < 5 * se + 1e-3 * expected.max()), \
            np.max(np.abs(mean - expected) / (se + 1e-12))


@pytest.mark.parametrize("rho_d,rho_s,n", [(0.3, 0.6, 20.0), ((0.9, 0.1, 0.2), (0.1, 0.9, 0.3), 30.0)])
def test_reported_pdf_is_the_pdf_and_eval_is_reciprocal(kernels, rho_d, rho_s, n):
    """Per sample: the pdf sample() reports equals pdf_bsdf, and eval is symmetric in (wo, wi)."""
    m = material(rho_d, rho_s, n)
    wo = direction(40)
    wi, weight = sample(kernels, m, wo, count=2000, seed=3)
    ok = weight[:, 3] > 0
    f, pdf = evaluate(kernels, m, wo, wi[ok])
    np.testing.assert_allclose(wi[ok, 3], pdf, rtol=1e-4)
    # reciprocity: f(wo, wi) == f(wi, wo)
    wo_vec = np.array([wo["x"], wo["y"], wo["z"]], np.float64)
    for k in np.flatnonzero(ok)[:50]:
        back, _ = evaluate(kernels, m, cltypes.make_float4(*wi[k, :3], 0), wo_vec[None])
        fwd, _ = evaluate(kernels, m, wo, wi[k:k + 1, :3])
        np.testing.assert_allclose(back, fwd, rtol=1e-4, atol=1e-7)
