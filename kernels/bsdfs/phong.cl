/* phong: the energy-conserving modified Phong BRDF (Lafortune & Willems, "Using the Modified
 * Phong Reflectance Model for Physically Based Rendering", 1994), the report's eq. (2):
 *     f(wo, wi) = rho_d / pi + rho_s (n + 2) / (2 pi) cos^n(alpha),
 * alpha the angle between wi and the mirror direction of wo, rho_d + rho_s <= 1 per channel.
 * Its parameters and the lobes' sampling probabilities, PHONG_DIFFUSE_SHARE and
 * PHONG_GLOSSY_SHARE (in the ratio max(rho_d) : max(rho_s), so that with the report's Russian
 * roulette every channel's weight stays <= 1), are read through accessors generated from their
 * slots on the host (app/materials/basic.py: Phong).
 *
 * Directions are in the local shading frame (z the normal); the surface is one-sided. */

float3 eval_phong(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    float exponent = PHONG_N(m);
    float cos_a = min(dot(wi, reflect_local(wo)), 1.0f);   /* rounding can exceed 1: cos^1e8 blows up */
    float glossy = cos_a > 0.0f ? (exponent + 2.0f) / (2.0f * PI_F) * pow(cos_a, exponent) : 0.0f;
    return PHONG_RHO_D(m) / PI_F + PHONG_RHO_S(m) * glossy;
}

/* The density of the directions sample_phong draws: the lobes' densities mixed. */
float pdf_phong(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    float cos_a = dot(wi, reflect_local(wo));
    return PHONG_DIFFUSE_SHARE(m) * pdf_cosine_hemisphere(wi.z) + PHONG_GLOSSY_SHARE(m) * pdf_cosine_power(cos_a, PHONG_N(m));
}

/* One lobe chosen by u.x, and the weight f cos / pdf of that lobe alone divided by its choice
 * probability (a one-sample estimator over the lobes, as in the report). A glossy direction
 * below the surface ends the path. */
int sample_phong(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    if (u.x < PHONG_DIFFUSE_SHARE(m)) {
        s->wi = sample_cosine_hemisphere(u.y, u.z);
        /* f_d cos / pdf = (rho_d / pi) cos / (cos / pi) = rho_d */
        s->weight = PHONG_RHO_D(m) / PHONG_DIFFUSE_SHARE(m);
        s->lobe = LOBE_DIFFUSE | LOBE_REFLECTION;
    } else {
        float exponent = PHONG_N(m);
        s->wi = to_world(sample_cosine_power(u.y, u.z, exponent), reflect_local(wo));
        if (s->wi.z <= 0.0f)
            return 0;
        /* f_s cos / pdf = rho_s (n + 2) / (n + 1) cos(theta_i): the cos^n factors cancel */
        s->weight = PHONG_RHO_S(m) * ((exponent + 2.0f) / (exponent + 1.0f) * s->wi.z / PHONG_GLOSSY_SHARE(m));
        s->lobe = LOBE_GLOSSY | LOBE_REFLECTION;
    }
    s->pdf = pdf_phong(m, wo, s->wi);
    return 1;
}
