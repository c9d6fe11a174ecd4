/* The energy-conserving modified Phong BRDF (Lafortune & Willems, "Using the Modified Phong
 * Reflectance Model for Physically Based Rendering", 1994), the report's eq. (2):
 *     f(wo, wi) = rho_d / pi + rho_s (n + 2) / (2 pi) cos^n(alpha),
 * alpha the angle between wi and the mirror direction of wo. All vectors point away from the
 * surface; n is the outward unit normal. Surfaces are one-sided: below it, f = 0.
 *
 * Lobe choice: with probability P_d the diffuse lobe, with P_s the glossy lobe, else the path is
 * absorbed (the report's Russian roulette on reflectance). P_d = max(rho_d), P_s = max(rho_s),
 * scaled so that P_d + P_s <= 1 (see app/types.py); the host stores them in diffuse.w and
 * emission.w. Without Russian roulette the two probabilities are renormalised to sum to one. */

float3 reflect_about(float3 w, float3 n)
{
    return 2.0f * dot(w, n) * n - w;
}

float3 eval_phong(const Material *m, float3 n, float3 wo, float3 wi)
{
    if (dot(n, wi) <= 0.0f || dot(n, wo) <= 0.0f)
        return (float3)(0.0f);
    float exponent = m->specular.w;
    float cos_a = dot(wi, reflect_about(wo, n));
    float glossy = cos_a > 0.0f ? (exponent + 2.0f) / (2.0f * PI_F) * pow(cos_a, exponent) : 0.0f;
    return m->diffuse.xyz / PI_F + m->specular.xyz * glossy;
}

/* The density of the directions sample_phong draws: the lobes' densities mixed in the ratio
 * P_d : P_s. Absorption (Russian roulette) and glossy draws below the surface, which end the
 * path, are separate from it. */
float pdf_phong(const Material *m, float3 n, float3 wo, float3 wi)
{
    float p_d = m->diffuse.w, p_s = m->emission.w;
    if (p_d + p_s <= 0.0f || dot(n, wi) <= 0.0f)
        return 0.0f;
    float cos_a = dot(wi, reflect_about(wo, n));
    return (p_d * pdf_cosine_hemisphere(dot(n, wi)) + p_s * pdf_cosine_power(cos_a, m->specular.w))
           / (p_d + p_s);
}

/* Draws wi and returns the path weight f cos(theta_i) / (P_lobe pdf_lobe(wi)) in *weight, using
 * only the chosen lobe's f (a one-sample estimator over the lobes, as in the report).
 * Returns 0 when the path ends: absorbed, or a glossy direction below the surface. */
int sample_phong(const Material *m, float3 n, float3 wo, float4 u, int russian_roulette,
                 float3 *wi, float3 *weight)
{
    float p_d = m->diffuse.w, p_s = m->emission.w;
    float total = russian_roulette ? 1.0f : p_d + p_s;
    float choice = u.x * total;
    if (choice < p_d) {
        *wi = to_world(sample_cosine_hemisphere(u.y, u.z), n);
        /* f_d cos / pdf = (rho_d / pi) cos / (cos / pi) = rho_d */
        *weight = m->diffuse.xyz * (total / p_d);
        return 1;
    }
    if (choice < p_d + p_s) {
        float exponent = m->specular.w;
        *wi = to_world(sample_cosine_power(u.y, u.z, exponent), reflect_about(wo, n));
        float cos_i = dot(*wi, n);
        if (cos_i <= 0.0f)
            return 0;
        /* f_s cos / pdf = rho_s (n + 2) / (n + 1) cos(theta_i): the cos^n factors cancel */
        *weight = m->specular.xyz * ((exponent + 2.0f) / (exponent + 1.0f) * cos_i * (total / p_s));
        return 1;
    }
    return 0;
}

/* The density with which BSDF sampling continues the path in direction wi: pdf_phong times the
 * probability of going on at all (P_d + P_s under Russian roulette, else 1). Multiple
 * importance sampling weighs light samples against it. */
float pdf_continue(const Material *m, float3 n, float3 wo, float3 wi, int russian_roulette)
{
    float go_on = russian_roulette ? m->diffuse.w + m->emission.w : 1.0f;
    return go_on * pdf_phong(m, n, wo, wi);
}
