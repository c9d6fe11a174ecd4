"""The GGX and Beckmann microfacet distributions on the host, mirroring kernels/microfacet.cl:
the roughness parameters the rough materials share, and the rough dielectric interface's
reflectance that roughplastic tabulates (Mitsuba 3 computes the same quantities at load time)."""

import math
from dataclasses import replace
from functools import lru_cache

import numpy as np

from pathtrace.materials.bsdf import Param
from pathtrace.materials.optics import fresnel_dielectric
from pathtrace.parameters import Parameter

GGX_PARAMS = (
    Param("alpha", "number", default=0.1, low=1e-4, high=1.0,
          doc="the microfacet roughness (Mitsuba's alpha: the root mean square slope)", pbrt_from="roughness"),
)


def anisotropic_params(alpha_slot: str, alpha_v_slot: str) -> tuple:
    """The roughness of a rough material that may be anisotropic (kernels/microfacet.cl), in
    the MATERIAL slots its kernel reads: alpha along the shading frame's tangent, dp/du (Mitsuba's
    alpha_u), and alpha_v along its bitangent, alpha where left out (AnisotropicRoughness)."""
    return (replace(GGX_PARAMS[0], slot=alpha_slot,
                    doc="the microfacet roughness (Mitsuba's alpha: the root mean square slope); "
                        "with alpha_v, the roughness along dp/du (Mitsuba's alpha_u)"),
            Param("alpha_v", "number", default=GGX_PARAMS[0].default, low=1e-4, high=1.0, slot=alpha_v_slot,
                  doc="the roughness along the bitangent; alpha where left out (isotropic)", pbrt_from="vroughness"))


class AnisotropicRoughness:
    """Of a BSDFType whose params include anisotropic_params: alpha_v follows alpha where a
    file leaves it out, and programs of scenes where the two differ (or may, where a texture
    gives them) keep a tangent per hit (ANISOTROPIC, kernels/frame.cl); the others cost nothing
    more."""
    variant_defines = ("ANISOTROPIC",)

    def resolve(self, values):
        values = super().resolve(values)
        if "alpha_v" not in values:
            values["alpha_v"] = values.get("alpha", GGX_PARAMS[0].default)
        return values

    def anisotropic(self, rows, alpha, alpha_v) -> bool:
        """Whether any of these rows, whose alphas are alpha and alpha_v, needs a tangent."""
        return bool(np.any((alpha != alpha_v) | (rows["textures"] >= 0)))

SMOOTH_ALPHA = 1e-3     # pbrt-v4's TrowbridgeReitzDistribution::EffectivelySmooth
PBRT_REMAP = Parameter(None, "bool", pbrt="remaproughness", pbrt_default=True,
                       doc="alpha = sqrt(roughness) (pbrt-v4's RoughnessToAlpha)")


def pbrt_roughness(prefix: str = "") -> tuple:
    """pbrt-v4's roughness parameters of a material (a layered one's prefixed `interface.` or
    `conductor.`): roughness, and uroughness and vroughness along dp/du and dp/dv, by default
    roughness (pbrt_alphas reads them)."""
    return (Parameter(None, "number", pbrt=prefix + "roughness", pbrt_default=0.0, doc="the microfacet roughness"),
            Parameter(None, "number", pbrt=prefix + "uroughness", pbrt_default="roughness", doc="along dp/du"),
            Parameter(None, "number", pbrt=prefix + "vroughness", pbrt_default="roughness", doc="along dp/dv"))


def pbrt_alphas(given: dict, prefix: str = "") -> tuple:
    """pbrt-v4's microfacet alphas (along dp/du and dp/dv, as its BSDF frame has them) from the
    values of pbrt_roughness(prefix) and PBRT_REMAP, by pbrt-v4's names. Raises ValueError
    ("<pbrt name>: <problem>")."""
    r = given[prefix + "roughness"]
    ru, rv = (r if isinstance(given[prefix + n], str) else given[prefix + n] for n in ("uroughness", "vroughness"))
    for name, v in (("roughness", r), ("uroughness", ru), ("vroughness", rv)):
        if v < 0 or v > 1e3 or not math.isfinite(v):
            raise ValueError(f"{prefix}{name}: must lie in [0, 1000], got {v:g}")
    return (math.sqrt(ru), math.sqrt(rv)) if given["remaproughness"] else (ru, rv)


def pbrt_rough(alphas) -> dict | None:
    """The alpha and alpha_v of a rough material (GGX, pbrt-v4's TrowbridgeReitz) for a pair of
    alphas, or None where pbrt-v4 deems them smooth (EffectivelySmooth: both below SMOOTH_ALPHA)."""
    if max(alphas) < SMOOTH_ALPHA:
        return None
    au, av = (min(max(a, 1e-4), 1.0) for a in alphas)
    return {"alpha": au, "alpha_v": av, "distribution": "ggx"}


# roughconductor's distribution: a number the kernel reads (kernels/bsdfs/roughconductor.cl),
# given by name
DISTRIBUTIONS = {"ggx": 0.0, "beckmann": 1.0}
DISTRIBUTION = Param("distribution", "number", default=0.0, low=0.0, high=1.0, names=DISTRIBUTIONS,
                     doc="the microfacet distribution: ggx (0) or beckmann (1; Mitsuba's default)",
                     mitsuba_default="beckmann")


def check_distribution(values) -> str | None:
    """The rough materials' distribution must be one of DISTRIBUTIONS' numbers."""
    if not np.all(np.isin(values["distribution"], list(DISTRIBUTIONS.values()))):
        return "distribution: must be ggx or beckmann"
    return None

# roughplastic's MATERIAL.table holds a function of cos(theta) at these cosines: (k / 15)^2,
# dense at grazing angles where the coating's transmittance changes fastest (16 samples there
# are as close to the exact curve as Mitsuba's 64 evenly spaced ones)
TABLE_SIZE = 16
TABLE_COSINES = np.maximum(1e-6, np.linspace(0.0, 1.0, TABLE_SIZE) ** 2)


def _dot(v, m):
    """The dot products of (..., 3) arrays, a component at a time: the sum np.sum(v * m, axis=-1)
    makes, in its order, without the (..., 3) product."""
    return v[..., 0] * m[..., 0] + v[..., 1] * m[..., 1] + v[..., 2] * m[..., 2]


def ggx_g1(v, m, alpha):
    """Smith's G1(v, m) = 2 / (1 + sqrt(1 + a^2 tan^2 theta_v)); 0 where v sees m's back."""
    cos2 = v[..., 2] ** 2
    tan2 = np.maximum(0.0, 1.0 - cos2) / np.maximum(cos2, 1e-30)
    g = 2.0 / (1.0 + np.sqrt(1.0 + alpha * alpha * tan2))
    return np.where(_dot(v, m) * v[..., 2] > 0, g, 0.0)


def sample_ggx_visible(wo, alpha, u1, u2):
    """Heitz 2018, listing 1, for one direction wo (wo.z > 0) and arrays of uniforms."""
    vh = np.array([alpha * wo[0], alpha * wo[1], wo[2]])
    vh /= np.linalg.norm(vh)
    len2 = vh[0] ** 2 + vh[1] ** 2
    t1 = np.array([-vh[1], vh[0], 0.0]) / np.sqrt(len2) if len2 > 0 else np.array([1.0, 0.0, 0.0])
    t2 = np.cross(vh, t1)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    p1, p2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1.0 + vh[2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * p2
    p3 = np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))
    # nh = p1 t1 + p2 t2 + p3 vh and m = nh unstretched and normalised, a component at a time
    # (the same sums in the same order as over (..., 3) arrays, at half their time)
    m = np.empty(p1.shape + (3,))
    for k in range(3):
        nh = p1 * t1[k] + p2 * t2[k] + p3 * vh[k]
        m[..., k] = alpha * nh if k < 2 else np.maximum(1e-6, nh)
    return m / np.sqrt(m[..., 0] * m[..., 0] + m[..., 1] * m[..., 1] + m[..., 2] * m[..., 2])[..., None]


def beckmann_g1(v, m, alpha):
    """Smith's G1 for Beckmann by Walter's rational approximation, as the kernels (and Mitsuba 3)."""
    xy = np.sqrt(v[..., 0] ** 2 + v[..., 1] ** 2)
    a = np.abs(v[..., 2]) / np.maximum(xy, 1e-30) / alpha
    g = np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a))
    return np.where(_dot(v, m) * v[..., 2] > 0, g, 0.0)


def erfinv_approx(x):
    """erf^-1(x) by Giles's single-precision approximation, as the kernels compute it."""
    x = np.asarray(x, np.float64)
    w = -np.log((1.0 - x) * (1.0 + x))
    small, big = w - 2.5, np.sqrt(np.maximum(w, 5.0)) - 3.0
    p_small = np.polyval([2.81022636e-08, 3.43273939e-07, -3.5233877e-06, -4.39150654e-06, 0.00021858087,
                          -0.00125372503, -0.00417768164, 0.246640727, 1.50140941], small)
    p_big = np.polyval([-0.000200214257, 0.000100950558, 0.00134934322, -0.00367342844, 0.00573950773,
                        -0.0076224613, 0.00943887047, 1.00167406, 2.83297682], big)
    return np.where(w < 5.0, p_small, p_big) * x


def sample_beckmann_visible(wo, alpha, u1, u2):
    """Jakob 2014's visible Beckmann normals, as kernels/microfacet.cl draws them, for one
    direction wo (wo.z > 0) and arrays of uniforms: a slope of the stretched direction by Newton's
    method on its CDF inside a bisection interval, turned to wo's azimuth and unstretched."""
    w = np.array([alpha * wo[0], alpha * wo[1], wo[2]])
    w /= np.linalg.norm(w)
    xy = np.hypot(w[0], w[1])
    cos_phi, sin_phi = (w[0] / xy, w[1] / xy) if xy > 0 else (1.0, 0.0)
    u1, u2 = np.maximum(u1, 1e-9), np.maximum(u2, 1e-9)
    if w[2] > 0.9999:
        r, phi = np.sqrt(-np.log(1.0 - u1)), 2 * np.pi * u2
        sx, sy = r * np.cos(phi), r * np.sin(phi)
    else:
        theta = np.arccos(w[2])
        tan_t, cot_t = np.tan(theta), 1.0 / np.tan(theta)
        lo, hi = np.full_like(u1, -1.0), np.full_like(u1, math.erf(cot_t))
        norm = 1.0 / (1.0 + math.erf(cot_t) + tan_t * np.exp(-cot_t * cot_t) / np.sqrt(np.pi))
        b = hi - (1.0 + hi) * (1.0 - u1) ** (1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta)))
        for _ in range(20):
            b = np.where((b >= lo) & (b <= hi), b, 0.5 * (lo + hi))
            e = erfinv_approx(np.clip(b, -1 + 1e-12, 1 - 1e-12))
            value = norm * (1.0 + b + tan_t * np.exp(-e * e) / np.sqrt(np.pi)) - u1
            hi, lo = np.where(value > 0, b, hi), np.where(value > 0, lo, b)
            step = value / (norm * (1.0 - e * tan_t))
            b = b - step
            # Newton's steps shrink quadratically, below 1e-12 after 4 to 6 of them for every
            # direction the tables ask for; the steps after that only move b by rounding (1e-15),
            # and stopping there spares two thirds of rough_coating's time
            if np.all(np.abs(step) < 1e-12):
                break
        sx, sy = erfinv_approx(np.clip(b, -1 + 1e-12, 1 - 1e-12)), erfinv_approx(np.clip(2.0 * u2 - 1.0, -1 + 1e-12, 1 - 1e-12))
    rx, ry = (cos_phi * sx - sin_phi * sy) * alpha, (sin_phi * sx + cos_phi * sy) * alpha
    m = np.stack([-rx, -ry, np.ones_like(rx)], axis=-1)
    return m / np.linalg.norm(m, axis=-1, keepdims=True)


def rough_dielectric_albedo(cos_theta, alpha, eta, nodes=None, beckmann=False, transmitted=True):
    """The fractions of light arriving at cos_theta (an array) that a rough dielectric interface
    (GGX, or Beckmann, of relative IOR eta = n_inside / n_outside) reflects and transmits, as two arrays: over
    visible normals m, E[F(wi.m) G1(wr, m)] and E[(1 - F(wi.m)) G1(wt, m)], wr and wt the
    mirrored and refracted directions (none where they leave on the wrong side); their sum is
    below 1 by what the microfacets shadow. Gauss-Legendre quadrature over the sampling square;
    total internal reflection (eta < 1) needs the finer rule. Without `transmitted`, the second
    array is not computed (None): a quarter of the time, which a scene's first reading waits for
    per roughplastic roughness (rough_coating)."""
    nodes = nodes or (32 if eta > 1 else 128)
    x, w = np.polynomial.legendre.leggauss(nodes)
    u1, u2 = np.meshgrid(0.5 * x + 0.5, 0.5 * x + 0.5)
    weight = np.outer(0.5 * w, 0.5 * w)
    reflected, passing = np.empty(len(cos_theta)), np.empty(len(cos_theta)) if transmitted else None
    for i, c in enumerate(cos_theta):
        wi = np.array([np.sqrt(max(0.0, 1.0 - c * c)), 0.0, c])
        m = (sample_beckmann_visible if beckmann else sample_ggx_visible)(wi, alpha, u1, u2)
        wi_m = m @ wi
        f = fresnel_dielectric(wi_m, eta)
        wr = 2.0 * wi_m[..., None] * m - wi
        g1 = beckmann_g1 if beckmann else ggx_g1
        reflected[i] = np.sum(np.where(wr[..., 2] > 0, f * g1(wr, m, alpha), 0.0) * weight)
        if transmitted:
            # Snell's law about m; under total internal reflection f = 1 and nothing passes
            cos_t = np.sqrt(np.maximum(0.0, 1.0 - (1.0 - wi_m ** 2) / eta ** 2))
            wt = -wi / eta + (wi_m / eta - cos_t)[..., None] * m
            passed = (1.0 - f) * g1(wt, m, alpha)
            passing[i] = np.sum(np.where(wt[..., 2] < 0, passed, 0.0) * weight)
    return reflected, passing


@lru_cache(maxsize=256)
def rough_coating(alpha: float, eta: float, beckmann: bool = False) -> tuple[np.ndarray, float]:
    """A rough dielectric coating's transmittance T(cos) at TABLE_COSINES (light entering from
    outside), and its cosine-weighted mean reflectance 2 int R(mu) mu dmu seen from inside
    (relative IOR 1/eta) -- roughplastic's two precomputed quantities, as Mitsuba 3's. The
    mean is Mitsuba's own rule, the average over 64 evenly spaced cosines including both ends:
    it sits about 0.01 below the integral (R is 1 up to the critical angle), and following it
    keeps roughplastic the same material in both renderers."""
    _, transmittance = rough_dielectric_albedo(TABLE_COSINES, alpha, eta, beckmann=beckmann)
    mu = np.maximum(1e-6, np.linspace(0.0, 1.0, 64))
    inside, _ = rough_dielectric_albedo(mu, alpha, 1.0 / eta, beckmann=beckmann, transmitted=False)
    return transmittance, float(2.0 * np.mean(inside * mu))
