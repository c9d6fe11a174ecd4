/* The Henyey-Greenstein phase function (Henyey and Greenstein, "Diffuse radiation in the
 * galaxy", ApJ 93, 1941), the phase function of Mitsuba 3's `hg` and `isotropic` (g = 0) and
 * pbrt-v4's media:
 *
 *   p(wo, wi) = (1 - g^2) / (4 pi (1 + g^2 + 2 g dot(wo, wi))^(3/2))
 *
 * with wo pointing back along the path (Mitsuba's and pbrt's convention): g > 0 scatters
 * forwards, towards wi = -wo; g < 0 backwards. It integrates to 1 over the sphere and is
 * sampled exactly, so a sample's weight p / pdf is 1. */

float eval_hg(float g, float3 wo, float3 wi)
{
    float denom = 1.0f + g * g + 2.0f * g * dot(wo, wi);
    return (1.0f - g * g) / (4.0f * PI_F * denom * sqrt(fmax(denom, 0.0f)));
}

/* A direction from p(wo, .) and its density, from two uniforms: the cosine mu between the
 * direction of travel -wo and wi inverts the distribution function of mu, whose density is
 * (1 - g^2) / (2 (1 + g^2 - 2 g mu)^(3/2)); uniform in mu where g is too small for that form's
 * precision. */
float3 sample_hg(float g, float3 wo, float2 u, float *pdf)
{
    float mu;
    if (fabs(g) < 1e-3f) {
        mu = 1.0f - 2.0f * u.x;
    } else {
        float s = (1.0f - g * g) / (1.0f - g + 2.0f * g * u.x);
        mu = (1.0f + g * g - s * s) / (2.0f * g);
    }
    mu = clamp(mu, -1.0f, 1.0f);
    float sin_mu = sqrt(fmax(0.0f, 1.0f - mu * mu));
    float3 wi = to_world((float3)(sin_mu * COS_TURNS(u.y), sin_mu * SIN_TURNS(u.y), mu), -wo);
    *pdf = eval_hg(g, wo, wi);
    return wi;
}
