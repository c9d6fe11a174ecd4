"""Every registered BSDF type, through the examples it declares (BSDFType.examples), by one
suite in the manner of Mitsuba 3's chi-square harness (mitsuba.chi2.BSDFAdapter): its sampling
against its pdf (a chi-square test over the whole sphere), the pdf's normalisation, the sample
weight against eval |cos| / pdf (draw by draw, and over every region of directions),
reciprocity, and energy conservation. A new type is tested by being registered. The cases of
every type are batched: one sampling launch per case, one quadrature launch for all of them
(the kernels below, one build). Its helpers (sample, evaluate, the grids) serve the closed-form
tests of test_materials.py and test_principled.py."""

import numpy as np
import pytest
from pyopencl import cltypes

from pathtrace.errors import UserError
from pathtrace.materials import BSDFS, DELTA, Material, pack
from pathtrace.scene import SceneBuilder
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
kernel void bsdf_pairs(global const Material *mat, global const float4 *wo, global const float4 *wi,
                       global float4 *out)
{
    int i = get_global_id(0);
    out[i] = (float4)(eval_bsdf(mat, wo[i].xyz, wi[i].xyz), pdf_bsdf(mat, wo[i].xyz, wi[i].xyz));
    /* a light sample's f and pdf from one switch (eval_pdf_bsdf) must be the same, to rounding
       (a compiler may contract the two inlined together otherwise), or the pair reads as NaN */
    float pdf;
    float3 f = eval_pdf_bsdf(mat, wo[i].xyz, wi[i].xyz, &pdf);
    if (any(fabs(f - out[i].xyz) > 1e-5f * fabs(out[i].xyz)) || fabs(pdf - out[i].w) > 1e-5f * fabs(out[i].w))
        out[i] = (float4)(NAN);
}
/* Per case c (material mat[c], outgoing wo[c]) and bin of ny x nphi: the integrals over the bin
 * of f |cos| (xyz) and of the pdf (w), by the midpoint rule on sub x sub cells. The bins are even
 * in y (the pole along y, away from lobes about the xz plane, where even steps stay fine in
 * angle) and in the azimuth atan2(z, x). */
kernel void bsdf_bins(global const Material *mat, global const float4 *wo, int ny, int nphi, int sub,
                      global float4 *out)
{
    int i = get_global_id(0), c = i / (ny * nphi), b = i % (ny * nphi);
    float dy = 2.0f / (ny * sub), dphi = 2.0f * M_PI_F / (nphi * sub);
    float4 sum = (float4)(0.0f);
    for (int j = 0; j < sub; ++j) {
        float y = -1.0f + ((b / nphi) * sub + j + 0.5f) * dy, s = sqrt(1.0f - y * y);
        for (int k = 0; k < sub; ++k) {
            float phi = -M_PI_F + ((b % nphi) * sub + k + 0.5f) * dphi;
            float3 wi = (float3)(s * cos(phi), y, s * sin(phi));
            sum += (float4)(eval_bsdf(&mat[c], wo[c].xyz, wi) * fabs(wi.z), pdf_bsdf(&mat[c], wo[c].xyz, wi));
        }
    }
    out[i] = sum * (dy * dphi);
}
"""
def direction(theta_deg, phi_deg=0.0):
    """The outgoing direction at theta degrees from the normal (and phi from the tangent), as a
    kernel argument."""
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return cltypes.make_float4(np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t), 0)


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


# -- the conformance suite --

COUNT = 100_000                       # draws per case
NY, NPHI = 32, 16                     # bins over the sphere (see bsdf_bins)
SUB = {False: 40, True: 12}           # quadrature cells per bin edge: exact types, estimated ones (at 28
                                      # the pdf of principled's sharpest example summed to 0.990, not 1)
PAIRS = 2000                          # draws per case whose eval, pdf and reverse are checked
ALPHA = 0.01                          # the chi-square tests' level, for all cases together
EXAMPLES = [(f"{name}-{k}", name, params) for name, bsdf in BSDFS.items() if bsdf.kernel and not bsdf.resolved_first
            for k, params in enumerate(bsdf.examples)]


def thetas(bsdf, values):
    """wo's angles from the normal: outside, and inside for a type seen from both sides."""
    return (15, 50, 78) + ((125, 165) if bsdf.transmits(values) else ())


def row(name, params):
    return pack(name, BSDFS[name].resolve(params))


def as_vectors(w):
    return np.array([[float(v[a]) for a in "xyz"] for v in w])


def evaluate_pairs(kernels, m, wo, wi):
    """eval and pdf at each pair (wo[i], wi[i]), at most PAIRS of them (launched over PAIRS
    work-items whatever their number: never an empty launch), each the same by eval_pdf_bsdf."""
    def four(v):
        padded = np.zeros((PAIRS, 4), np.float32)
        padded[:len(v), :3], padded[len(v):, 2] = v[:, :3], 1.0
        return padded
    out = np.zeros((PAIRS, 4), np.float32)
    kernels(SOURCE)("bsdf_pairs", PAIRS, m, four(wo), four(wi), out)
    assert not np.isnan(out).any(), "eval_pdf_bsdf differs from eval_bsdf and pdf_bsdf"
    return out[:len(wi), :3].astype(np.float64), out[:len(wi), 3].astype(np.float64)


def bins_of(w):
    """Each direction's bin of bsdf_bins, and whether it has one (a direction drawn)."""
    y = np.clip(((w[:, 1] + 1) / 2 * NY).astype(int), 0, NY - 1)
    phi = np.clip(((np.arctan2(w[:, 2], w[:, 0]) + np.pi) / (2 * np.pi) * NPHI).astype(int), 0, NPHI - 1)
    return y * NPHI + phi


def quadrature(kernels, rows, wo, sub):
    """Per case and bin: the integrals of f |cos| (rgb) and of the pdf."""
    out = np.zeros((len(rows) * NY * NPHI, 4), np.float32)
    wo4 = np.array([[v["x"], v["y"], v["z"], 0] for v in wo], np.float32)
    kernels(SOURCE)("bsdf_bins", len(out), np.concatenate(rows), wo4, np.int32(NY), np.int32(NPHI),
                    np.int32(sub), out)
    return out.reshape(len(rows), NY * NPHI, 4).astype(np.float64)


@pytest.fixture(scope="module")
def cases(kernels):
    """For every example and wo: the draws' statistics per bin, and the first PAIRS draws."""
    found = {}
    for key, name, params in EXAMPLES:
        bsdf, m = BSDFS[name], row(name, params)
        transmits = bsdf.transmits(bsdf.complete(params))
        for theta in thetas(bsdf, bsdf.complete(params)):
            wo = direction(theta, 30)
            wi, weight = sample(kernels, m, wo, count=COUNT, seed=theta)
            smooth = weight[:, 3] == 1
            where = bins_of(wi[smooth])
            per_bin = lambda v: np.bincount(where, v, NY * NPHI)     # noqa: E731
            found[key, theta] = {
                "name": name, "m": m, "wo": wo, "transmits": transmits, "smooth": smooth.mean(),
                "crossed": np.count_nonzero(smooth & (np.sign(wi[:, 2]) != np.sign(wo["z"]))),
                "counts": per_bin(None), "wi": wi[:PAIRS], "weight": weight[:PAIRS],
                "sums": np.stack([per_bin(weight[smooth, c]) for c in range(3)], -1),
                "squares": np.stack([per_bin(weight[smooth, c].astype(np.float64) ** 2) for c in range(3)], -1),
                "total": weight[:, :3].mean(axis=0), "total_se": weight[:, :3].std(axis=0) / np.sqrt(COUNT)}
    for estimated in (False, True):
        keys = [k for k, c in found.items() if BSDFS[c["name"]].estimated == estimated
                and not BSDFS[c["name"]].flags & DELTA]
        if keys:
            q = quadrature(kernels, [found[k]["m"] for k in keys], [found[k]["wo"] for k in keys], SUB[estimated])
            for k, b in zip(keys, q):
                found[k]["f_cos"], found[k]["pdf"] = b[:, :3], b[:, 3]
    return found


def of(cases, key, smooth=True):
    """The cases of example `key` (for smooth=True, of a type with non-delta lobes)."""
    chosen = [c for (k, _), c in cases.items() if k == key]
    return [c for c in chosen if "pdf" in c] if smooth else chosen


SMOOTH = [key for key, name, _ in EXAMPLES if not BSDFS[name].flags & DELTA]
EXACT = [key for key, name, _ in EXAMPLES if not BSDFS[name].flags & DELTA and not BSDFS[name].estimated]
DELTAS = [key for key, name, _ in EXAMPLES if BSDFS[name].flags & DELTA]


def test_every_registered_type_declares_examples_that_pack_and_unpack():
    """Each type its own examples (not a parent's), each complete, and the viewer's editor's round
    trip (unpack a row, pack it again) keeps its row."""
    for name, bsdf in BSDFS.items():
        assert type(bsdf).__dict__.get("examples"), f"{name} declares no examples"
        for params in bsdf.examples:
            rows = row(name, params)
            again = pack(name, bsdf.unpack(rows[0]))
            for field in rows.dtype.names:
                np.testing.assert_allclose(again[field], rows[field], rtol=1e-6, err_msg=f"{name}.{field}")


def test_a_parameter_a_type_lacks_or_a_required_one_left_out_is_refused_not_packed_as_nan():
    """pack and the scene builder's materials: a name the type does not have (a format's name,
    Mitsuba's "reflectance" for rho_d) or a parameter without a default left out raises, naming
    the type and the parameter (a UserError naming the row where a scene's row is set), where
    both packed NaN (a diffuse emitter so packed made NEE and BDPT disagree with paths alone,
    each dropping the samples it happened to)."""
    for name, bsdf in BSDFS.items():
        with pytest.raises(ValueError, match=f"^{name}: unknown parameter 'no_such_parameter'"):
            pack(name, {**bsdf.examples[0], "no_such_parameter": 1.0})
        for example in bsdf.examples:
            for p in bsdf.params:
                if p.name in example and p.kind != "name" and p.into is None and p.default is None:
                    with pytest.raises(ValueError, match=f"^{name}: missing '{p.name}'"):
                        pack(name, {k: v for k, v in example.items() if k != p.name})
    b = SceneBuilder()
    with pytest.raises(ValueError, match="^diffuse: unknown parameter 'reflectance'"):
        b.material(Material("diffuse", {"reflectance": 0.8}, emission=np.full(3, 0.5)))
    # the API's scene.materials[k] = ...: one line naming the row (docs/python.md)
    k = b.material(Material("diffuse", {"rho_d": 0.8}))
    with pytest.raises(UserError, match=rf"^materials\[{k}\]: diffuse: unknown parameter 'reflectance'"):
        b.materials[k] = Material("diffuse", {"reflectance": 0.8})


def test_every_type_with_a_bsdf_kernel_is_in_the_suite():
    assert {name for _, name, _ in EXAMPLES} == {n for n, b in BSDFS.items() if b.kernel and not b.resolved_first}


@pytest.mark.parametrize("key", EXACT)
def test_sampling_follows_the_pdf_over_the_sphere(cases, key):
    """The non-delta draws' histogram matches the pdf integrated over each bin (chi-square, at
    level ALPHA over all cases of the suite, Sidak-corrected)."""
    tests = sum(len(of(cases, k)) for k in EXACT)
    threshold = 1 - (1 - ALPHA) ** (1 / tests)
    for c in of(cases, key):
        expected = c["pdf"] * COUNT
        p = chi_square(c["counts"], expected)
        assert p > threshold, (c["wo"], p, threshold)


@pytest.mark.parametrize("key", EXACT)
def test_the_pdf_integrates_to_the_share_of_draws_that_gave_a_direction(cases, key):
    """The pdf's integral over the sphere is the probability that a draw yields a non-delta
    direction (the rest went to a delta lobe or below the surface), at most 1; a surface that
    transmits nothing draws no direction through it."""
    for c in of(cases, key):
        total = c["pdf"].sum()
        se = np.sqrt(c["smooth"] * (1 - c["smooth"]) / COUNT)
        assert abs(total - c["smooth"]) < 5 * se + 2e-3, (c["wo"], total, c["smooth"])
        assert total <= 1 + 2e-3
        assert c["transmits"] or c["crossed"] == 0


@pytest.mark.parametrize("key", SMOOTH)
def test_weights_carry_f_cos_into_every_region(cases, key):
    """Over any region of directions, the sum of the weights of the draws that land there, over
    the number drawn, estimates the integral of f |cos| over it (whatever the weights' form, per
    lobe or not): per bin, with each bin's standard error. For a type whose f is an estimate, over
    the whole sphere, where the quadrature's own noise averages out."""
    for c in of(cases, key):
        mean = c["sums"] / COUNT
        se = np.sqrt(np.maximum(c["squares"] / COUNT - mean ** 2, 0) / COUNT)
        if BSDFS[c["name"]].estimated:
            total, albedo = mean.sum(axis=0), c["f_cos"].sum(axis=0)
            assert np.all(np.abs(total - albedo) < 5 * np.sqrt((se ** 2).sum(axis=0)) + 0.01 * albedo + 2e-3), \
                (c["wo"], total, albedo)
        else:
            # where few draws land, their sample variance understates the error: a bin's k
            # expected draws (pdf x COUNT) carry weights whose sum has a variance of at least
            # (integral of f |cos|)^2 / k, the count's Poisson noise alone
            expected = np.maximum(c["pdf"] * COUNT, 1)[:, None]
            se = np.maximum(se, c["f_cos"] / np.sqrt(expected))
            gap = np.abs(mean - c["f_cos"]) - 5 * se - 1e-3 * c["f_cos"].max()
            assert np.all(gap < 0), (c["wo"], np.max(np.abs(mean - c["f_cos"]) / (se + 1e-12)))
            # and no direction where f is seen is one that sampling never draws
            assert not np.any((c["f_cos"].max(axis=1) > 1e-3 * c["f_cos"].max()) & (c["pdf"] == 0)), c["wo"]


@pytest.mark.parametrize("key", SMOOTH)
def test_each_draw_reports_pdf_bsdf_and_weighs_eval_cos_over_pdf(kernels, cases, key):
    """Draw by draw: the pdf sample() reports is pdf_bsdf's (MIS divides by it), and the weight is
    eval |cos| / pdf, but for a type that weighs by the chosen lobe (lobe_weights) or estimates
    f (estimated)."""
    for c in of(cases, key):
        ok = c["weight"][:, 3] == 1
        wo = np.broadcast_to(as_vectors([c["wo"]]), (ok.sum(), 3))
        f, pdf = evaluate_pairs(kernels, c["m"], wo, c["wi"][ok])
        np.testing.assert_allclose(c["wi"][ok, 3], pdf, rtol=2e-4)
        bsdf = BSDFS[c["name"]]
        if not (bsdf.lobe_weights or bsdf.estimated):
            np.testing.assert_allclose(c["weight"][ok, :3], f * np.abs(c["wi"][ok, 2:3]) / pdf[:, None], rtol=2e-3, atol=1e-6)


@pytest.mark.parametrize("key", EXACT)
def test_eval_is_reciprocal(kernels, cases, key):
    """f(wo, wi) = f(wi, wo) at the directions drawn: for every pair of a reciprocal type, and the
    reflected ones of a refracting type."""
    for c in of(cases, key):
        ok = c["weight"][:, 3] == 1
        wi = c["wi"][ok, :3]
        wo = np.broadcast_to(as_vectors([c["wo"]]), wi.shape)
        if not BSDFS[c["name"]].reciprocal:
            same = np.sign(wi[:, 2]) == np.sign(wo[:, 2])
            wi, wo = wi[same], wo[same]
        forward, _ = evaluate_pairs(kernels, c["m"], wo, wi)
        back, _ = evaluate_pairs(kernels, c["m"], wi, wo)
        np.testing.assert_allclose(back, forward, rtol=2e-3, atol=1e-7)


@pytest.mark.parametrize("key", [key for key, _, _ in EXAMPLES])
def test_a_surface_that_transmits_nothing_reflects_at_most_what_it_receives(cases, key):
    """The mean weight of all draws (delta ones included) is the directional albedo: at most 1 for
    a type that only reflects (refraction's radiance scaling makes a transmitted weight exceed 1
    legitimately)."""
    for c in of(cases, key, smooth=False):
        if not c["transmits"]:
            assert np.all(c["total"] <= 1 + 5 * c["total_se"] + 1e-3), (c["wo"], c["total"])


@pytest.mark.parametrize("key", DELTAS)
def test_a_delta_type_draws_only_deltas(kernels, cases, key):
    """Every draw of a type whose every lobe is a delta is a delta one, and eval and pdf are 0
    there (no light sampling can meet it)."""
    for c in of(cases, key, smooth=False):
        assert c["smooth"] == 0
        ok = c["weight"][:, 3] == 2
        wo = np.broadcast_to(as_vectors([c["wo"]]), (ok.sum(), 3))
        f, pdf = evaluate_pairs(kernels, c["m"], wo, c["wi"][ok])
        assert not f.any() and not pdf.any()
