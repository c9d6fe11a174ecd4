/* An interface between two dielectrics, smooth or rough, as a building block: the surface of
 * kernels/bsdfs/roughdielectric.cl and the coating of kernels/bsdfs/coateddiffuse.cl. Light is
 * reflected with the Fresnel reflectance F and refracted otherwise, by one mirror (smooth:
 * alpha 0) or by microfacets of a GGX or Beckmann distribution (Walter et al., "Microfacet
 * Models for Refraction through Rough Surfaces", EGSR 2007, eqs. 20-21):
 *   reflection    f = F(wo.h) D(h) G / (4 |wo.z| |wi.z|),                  h ~ wo + wi
 *   transmission  f = (1 - F(wo.h)) D(h) G |wo.h| |wi.h| e^2 / (|wo.z| |wi.z| (wo.h + e wi.h)^2),
 *                                                                          h ~ wo + e wi
 * with e = n(wi's side) / n(wo's side) and h turned outside. This transmission is radiance's
 * without its (n_wo / n_wi)^2 compression, which the callers apply where they need it (a layer
 * entered and left by the same side has none). `lobes` restricts an evaluation or a sample to
 * reflection (LOBE_REFLECTION), transmission (LOBE_TRANSMISSION), or both, as pbrt-v4's
 * BxDFReflTransFlags do for its layered BSDF. */

typedef struct {
    float eta;       /* n inside (below the surface) / n outside */
    float2 alpha;    /* the roughness along the tangent and the bitangent; (0, 0): smooth */
    int beckmann;    /* the distribution: 1 Beckmann, 0 GGX */
} Interface;

int is_smooth(Interface c)
{
    return c.alpha.x == 0.0f;
}

float interface_d(Interface c, float3 h)
{
    return c.beckmann ? beckmann_d(h, c.alpha) : ggx_d(h, c.alpha);
}

float interface_g1(Interface c, float3 v, float3 h)
{
    return c.beckmann ? beckmann_g1(v, h, c.alpha) : ggx_g1(v, h, c.alpha);
}

/* The density of the normal h (outside) that sampling draws, visible from wo's side (wo
 * mirrored outside when it is inside, as Mitsuba 3 does) */
float interface_normal_pdf(Interface c, float3 wo, float3 h)
{
    float3 up = wo.z > 0.0f ? wo : -wo;
    return c.beckmann ? pdf_beckmann_visible(up, h, c.alpha) : pdf_ggx_visible(up, h, c.alpha);
}

/* f(wo, wi) of the rough interface (without radiance compression) restricted to `lobes`, and
 * in *pdf the density with which sample_interface draws wi from wo under the same restriction;
 * 0 for a smooth one. */
float eval_interface(Interface c, float3 wo, float3 wi, int lobes, float *pdf)
{
    *pdf = 0.0f;
    int reflect = wo.z * wi.z > 0.0f;
    if (is_smooth(c) || wo.z == 0.0f || wi.z == 0.0f
        || !(lobes & (reflect ? LOBE_REFLECTION : LOBE_TRANSMISSION)))
        return 0.0f;
    float e = reflect ? 1.0f : (wo.z > 0.0f ? c.eta : 1.0f / c.eta);
    float3 h = unit(wo + e * wi);
    h = h.z < 0.0f ? -h : h;
    float wo_h = dot(wo, h), wi_h = dot(wi, h);
    /* the microfacet must face wo and wi from the sides they lie on */
    if (wo_h * wo.z <= 0.0f || wi_h * wi.z <= 0.0f)
        return 0.0f;
    float cos_t, eta_ti;
    float fr = fresnel_dielectric(wo_h, c.eta, &cos_t, &eta_ti);
    /* the chosen lobe's probability: F or 1 - F, or 1 where the other lobe is excluded */
    float choice = lobes == (LOBE_REFLECTION | LOBE_TRANSMISSION) ? (reflect ? fr : 1.0f - fr) : 1.0f;
    float d = interface_d(c, h), pdf_h = interface_normal_pdf(c, wo, h);
    float g = interface_g1(c, wo, h) * interface_g1(c, wi, h);
    if (reflect) {
        *pdf = pdf_h * choice / (4.0f * fabs(wo_h));
        return fr * d * g / (4.0f * fabs(wo.z * wi.z));
    }
    float denom = wo_h + e * wi_h;
    float jacobian = e * e * fabs(wi_h) / (denom * denom);       /* Walter et al., eq. 17 */
    *pdf = pdf_h * choice * jacobian;
    return (1.0f - fr) * d * g * fabs(wo_h) * jacobian / fabs(wo.z * wi.z);
}

/* Draws wi from wo under `lobes` (two uniforms for the normal, one for the lobe): s->weight.x
 * is f |cos| / pdf without radiance compression (the lobe's choice included), s->eta n_t / n_i
 * across a refraction, s->lobe LOBE_DELTA for a smooth interface. Returns 0 when no direction
 * results. */
int sample_interface(Interface c, float3 wo, float3 u, int lobes, BSDFSample *s)
{
    if (wo.z == 0.0f)
        return 0;
    float3 up = wo.z > 0.0f ? wo : -wo;
    float3 h = is_smooth(c) ? (float3)(0.0f, 0.0f, 1.0f)
             : c.beckmann ? sample_beckmann_visible(up, c.alpha, u.y, u.z) : sample_ggx_visible(up, c.alpha, u.y, u.z);
    float wo_h = dot(wo, h);
    float cos_t, eta_ti;
    float fr = fresnel_dielectric(wo_h, c.eta, &cos_t, &eta_ti);
    float p_reflect = lobes == LOBE_REFLECTION ? 1.0f : lobes == LOBE_TRANSMISSION ? 0.0f : fr;
    float g = 1.0f;
    if (u.x < p_reflect) {
        if (fr == 0.0f)
            return 0;
        s->wi = 2.0f * wo_h * h - wo;
        s->eta = 1.0f;
        s->lobe = LOBE_REFLECTION;
        s->weight = (float3)(fr / p_reflect);
    } else {
        if (fr == 1.0f)
            return 0;                                 /* total internal reflection only */
        /* Snell's law about h: the tangential part turned round and scaled by n_i / n_t */
        s->wi = (eta_ti * wo_h + cos_t) * h - eta_ti * wo;
        s->eta = 1.0f / eta_ti;
        s->lobe = LOBE_TRANSMISSION;
        s->weight = (float3)((1.0f - fr) / (1.0f - p_reflect));
    }
    if (is_smooth(c)) {
        s->pdf = (s->lobe & LOBE_REFLECTION) ? p_reflect : 1.0f - p_reflect;
        s->lobe |= LOBE_DELTA;
        return 1;
    }
    if ((s->lobe & LOBE_REFLECTION) ? s->wi.z * wo.z <= 0.0f : s->wi.z * wo.z >= 0.0f)
        return 0;
    /* the microfacet sample's weight: G1(wi, h) times the lobe's (Heitz 2018, eq. 18) */
    s->weight *= interface_g1(c, s->wi, h);
    eval_interface(c, wo, s->wi, lobes, &s->pdf);
    s->lobe |= LOBE_GLOSSY;
    return s->pdf > 0.0f;
}
