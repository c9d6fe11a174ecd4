/* roughdielectric: a rough interface between two dielectrics, such as frosted or etched glass
 * (Mitsuba 3's `roughdielectric`; pbrt-v4's `dielectric` with a roughness): the microfacet
 * model of Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007,
 * with the GGX or Beckmann distribution (kernels/microfacet.cl) and Smith's separable shadowing:
 *   reflection    f = R F(wo.h) D(h) G / (4 |wo.z| |wi.z|),                h ~ wo + wi
 *   transmission  f = T (1 - F(wo.h)) D(h) G |wo.h| |wi.h| / (|wo.z| |wi.z| (wo.h + e wi.h)^2),
 *                                                                          h ~ wo + e wi
 * with e = n(wi's side) / n(wo's side) and h turned to the outside (Walter's eqs. 20-21 for
 * radiance, whose transmission holds the (n_wo / n_wi)^2 compression of the smooth dielectric).
 *
 * Parameters (Material):
 *   p0.x    int_ior, the IOR inside (opposite the normal)     p0.y  ext_ior, outside
 *   p0.z    alpha, the roughness                              p0.w  1 for Beckmann, 0 for GGX
 *   p1.xyz  specular_reflectance R, a factor on reflection
 *   p2.xyz  specular_transmittance T, a factor on transmission
 *
 * Transmissive: wo may lie on either side. Sampling draws a normal visible from wo (mirrored
 * to the outside when wo is inside, as Mitsuba 3 does), then reflects with the probability
 * F(wo.h) or refracts: the weight is R G1(wi, h), or T G1(wi, h) / e^2. Beckmann's code is
 * compiled only where a scene has it (BECKMANN). */

#ifdef BECKMANN
#define ROUGH_GLASS_IS_BECKMANN(m) ((m)->p0.w > 0.5f)
#else
#define ROUGH_GLASS_IS_BECKMANN(m) 0
#endif

float rough_glass_d(MaterialRef m, float3 h)
{
    return ROUGH_GLASS_IS_BECKMANN(m) ? beckmann_d(h, m->p0.z) : ggx_d(h, m->p0.z);
}

float rough_glass_g1(MaterialRef m, float3 v, float3 h)
{
    return ROUGH_GLASS_IS_BECKMANN(m) ? beckmann_g1(v, h, m->p0.z) : ggx_g1(v, h, m->p0.z);
}

/* The density of the normal h (outside) that sampling draws from wo, seen from wo's side */
float pdf_rough_glass_normal(MaterialRef m, float3 wo, float3 h)
{
    float3 up = wo.z > 0.0f ? wo : -wo;
    return ROUGH_GLASS_IS_BECKMANN(m) ? pdf_beckmann_visible(up, h, m->p0.z) : pdf_ggx_visible(up, h, m->p0.z);
}

/* The microfacet normal between wo and wi (turned outside), and e = n(wi's side) / n(wo's side) */
float3 rough_glass_half(MaterialRef m, float3 wo, float3 wi, float *e)
{
    float eta = m->p0.x / m->p0.y;
    *e = wo.z * wi.z > 0.0f ? 1.0f : (wo.z > 0.0f ? eta : 1.0f / eta);
    float3 h = unit(wo + *e * wi);
    return h.z < 0.0f ? -h : h;
}

float3 eval_roughdielectric(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z == 0.0f || wi.z == 0.0f)
        return (float3)(0.0f);
    float e;
    float3 h = rough_glass_half(m, wo, wi, &e);
    float wo_h = dot(wo, h), wi_h = dot(wi, h);
    float g = rough_glass_g1(m, wo, h) * rough_glass_g1(m, wi, h);
    float cos_t, eta_ti;
    float f = fresnel_dielectric(wo_h, m->p0.x / m->p0.y, &cos_t, &eta_ti);
    float d = rough_glass_d(m, h);
    if (wo.z * wi.z > 0.0f)
        return m->p1.xyz * (f * d * g / (4.0f * fabs(wo.z * wi.z)));
    float denom = wo_h + e * wi_h;
    return m->p2.xyz * ((1.0f - f) * d * g * fabs(wo_h * wi_h) / (fabs(wo.z * wi.z) * denom * denom));
}

/* Reflection: pdf(h) F / (4 |wo.h|); transmission: pdf(h) (1 - F) e^2 |wi.h| / (wo.h + e wi.h)^2,
 * the Jacobians of Walter et al.'s eqs. 14 and 17 */
float pdf_roughdielectric(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z == 0.0f || wi.z == 0.0f)
        return 0.0f;
    float e;
    float3 h = rough_glass_half(m, wo, wi, &e);
    float wo_h = dot(wo, h), wi_h = dot(wi, h);
    /* the microfacet must face wo and wi from the sides they lie on */
    if (wo_h * wo.z <= 0.0f || wi_h * wi.z <= 0.0f)
        return 0.0f;
    float cos_t, eta_ti;
    float f = fresnel_dielectric(wo_h, m->p0.x / m->p0.y, &cos_t, &eta_ti);
    float pdf_h = pdf_rough_glass_normal(m, wo, h);
    if (wo.z * wi.z > 0.0f)
        return pdf_h * f / (4.0f * fabs(wo_h));
    float denom = wo_h + e * wi_h;
    return pdf_h * (1.0f - f) * e * e * fabs(wi_h) / (denom * denom);
}

int sample_roughdielectric(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z == 0.0f)
        return 0;
    float3 up = wo.z > 0.0f ? wo : -wo;
    float alpha = m->p0.z;
    float3 h = ROUGH_GLASS_IS_BECKMANN(m) ? sample_beckmann_visible(up, alpha, u.y, u.z)
                                          : sample_ggx_visible(up, alpha, u.y, u.z);
    float wo_h = dot(wo, h);
    float cos_t, eta_ti;
    float f = fresnel_dielectric(wo_h, m->p0.x / m->p0.y, &cos_t, &eta_ti);
    float pdf_h = pdf_rough_glass_normal(m, wo, h);
    if (u.x < f) {
        s->wi = 2.0f * wo_h * h - wo;
        if (s->wi.z * wo.z <= 0.0f)
            return 0;
        s->pdf = pdf_h * f / (4.0f * fabs(wo_h));
        s->weight = m->p1.xyz * rough_glass_g1(m, s->wi, h);
        s->eta = 1.0f;
        s->lobe = LOBE_GLOSSY | LOBE_REFLECTION;
    } else {
        /* Snell's law about h: the tangential part turned round and scaled by n_i / n_t */
        s->wi = (eta_ti * wo_h + cos_t) * h - eta_ti * wo;
        if (s->wi.z * wo.z >= 0.0f)
            return 0;
        float wi_h = dot(s->wi, h), e = 1.0f / eta_ti;
        float denom = wo_h + e * wi_h;
        s->pdf = pdf_h * (1.0f - f) * e * e * fabs(wi_h) / (denom * denom);
        s->weight = m->p2.xyz * (rough_glass_g1(m, s->wi, h) * eta_ti * eta_ti);
        s->eta = e;
        s->lobe = LOBE_GLOSSY | LOBE_TRANSMISSION;
    }
    return s->pdf > 0.0f;
}
