/* A homogeneous participating medium (Mitsuba 3's `homogeneous`, pbrt-v4's "homogeneous"): the
 * same coefficients everywhere inside the shapes that bound it, per RGB channel.
 *
 *   sigma_s.xyz   scattering coefficient, per unit length of the scene
 *   sigma_s.w     g, the mean cosine of its Henyey-Greenstein phase function (kernels/phase.cl;
 *                 0: isotropic)
 *   sigma_t.xyz   extinction coefficient sigma_a + sigma_s
 *
 * Where a heterogeneous (grid) medium would go: a type tag in Medium, its own file here with the
 * same two functions, sampling distances by delta tracking against a majorant and transmittance
 * by ratio tracking (Novak et al., "Monte Carlo Methods for Volumetric Light Transport
 * Simulation", 2018); kernels/volume.cl would dispatch on the tag. */

/* Transmittance over distance t, exp(-sigma_t t) per channel (Beer-Lambert); a channel that
 * nothing attenuates transmits everything, to t = inf too (where 0 inf is NaN). */
float3 medium_transmittance(const global Medium *m, float t)
{
    float3 sigma_t = m->sigma_t.xyz;
    return select(exp(-sigma_t * t), (float3)(1.0f), sigma_t == 0.0f);
}

typedef struct {
    float3 weight;    /* the estimate's factor for the hero channel's sampling: Tr sigma_s / p_c at
                         a scattering, Tr / p_c on reaching t_max */
    float3 ratio;     /* each channel's density of the same event over the hero's, p_k / p_c */
    float t;          /* the distance reached */
    int scattered;    /* 1: the path scatters at t inside the medium */
} FreeFlight;

/* Where along a ray whose nearest surface is t_max away the path next scatters, from one
 * uniform: a distance of density sigma_c exp(-sigma_c t) in the path's hero channel c. The
 * integrator weighs the channels' estimates by one-sample MIS over whole paths (the balance
 * heuristic over the three channels' path densities: "spectral MIS", Miller, Georgiev and
 * Jarosz, "A null-scattering path integral formulation of light transport", SIGGRAPH 2019,
 * and pbrt-v4's rescaled path probabilities r_u), for which each event reports every channel's
 * density relative to the hero's. Averaging per event instead multiplies ratios of up to 3 along
 * a path, whose heavy tail a furnace test showed. */
FreeFlight sample_free_flight(const global Medium *m, float t_max, int hero, float u)
{
    float3 sigma_t = m->sigma_t.xyz;
    float sigma = hero == 0 ? sigma_t.x : hero == 1 ? sigma_t.y : sigma_t.z;
    float t = sigma > 0.0f ? -log1p(-u) / sigma : INFINITY;
    FreeFlight f;
    f.scattered = t < t_max;
    f.t = fmin(t, t_max);
    float3 tr = medium_transmittance(m, f.t);
    /* each channel's density of scattering at t, or its probability of flying past t_max */
    float3 pdf = f.scattered ? sigma_t * tr : tr;
    float pdf_hero = hero == 0 ? pdf.x : hero == 1 ? pdf.y : pdf.z;
    f.weight = (f.scattered ? m->sigma_s.xyz * tr : tr) / pdf_hero;
    f.ratio = pdf / pdf_hero;
    return f;
}
