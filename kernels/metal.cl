/* A metal surface as a building block: the surface of kernels/bsdfs/roughconductor.cl and the
 * base of kernels/bsdfs/coatedconductor.cl. Light is reflected with the conductor Fresnel
 * reflectance F of the complex IOR eta + i k (kernels/fresnel.cl), by one mirror (smooth:
 * alpha 0) or by microfacets of a GGX or Beckmann distribution (kernels/microfacet.cl):
 *     f(wo, wi) = F(wo.h) D(h) G1(wo, h) G1(wi, h) / (4 cos(theta_o) cos(theta_i)),
 * sampled by visible normals, whose weight f cos / pdf is F(wo.h) G1(wi, h). One-sided: both
 * directions above the surface. */

typedef struct {
    float3 eta;      /* the real part of the complex IOR */
    float3 k;        /* its imaginary part */
    float2 alpha;    /* the roughness along the tangent and the bitangent; (0, 0): a mirror */
    int beckmann;    /* the distribution: 1 Beckmann, 0 GGX */
} Metal;

float metal_d(Metal c, float3 h)
{
    return c.beckmann ? beckmann_d(h, c.alpha) : ggx_d(h, c.alpha);
}

float metal_g1(Metal c, float3 v, float3 h)
{
    return c.beckmann ? beckmann_g1(v, h, c.alpha) : ggx_g1(v, h, c.alpha);
}

/* The density, per solid angle of h, of the normal that sampling draws from wo */
float metal_normal_pdf(Metal c, float3 wo, float3 h)
{
    return c.beckmann ? pdf_beckmann_visible(wo, h, c.alpha) : pdf_ggx_visible(wo, h, c.alpha);
}

/* f(wo, wi) of a rough metal; 0 for a mirror */
float3 eval_metal(Metal c, float3 wo, float3 wi)
{
    if (c.alpha.x == 0.0f || wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    float3 h = unit(wo + wi);
    float g = metal_g1(c, wo, h) * metal_g1(c, wi, h);
    return fresnel_conductor(dot(wo, h), c.eta, c.k) * (metal_d(c, h) * g / (4.0f * wo.z * wi.z));
}

/* pdf(wi) = pdf(h) / (4 wo.h), the Jacobian of reflection (Walter et al. 2007, eq. 14); 0 for a
 * mirror */
float pdf_metal(Metal c, float3 wo, float3 wi)
{
    if (c.alpha.x == 0.0f || wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    float3 h = unit(wo + wi);
    float wo_h = dot(wo, h);
    return wo_h > 0.0f ? metal_normal_pdf(c, wo, h) / (4.0f * wo_h) : 0.0f;
}

/* Draws wi from wo with two uniforms: a mirror's reflection (LOBE_DELTA, pdf 1) or a visible
 * microfacet's. Returns 0 when no direction results. */
int sample_metal(Metal c, float3 wo, float2 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    s->eta = 1.0f;
    if (c.alpha.x == 0.0f) {
        s->wi = reflect_local(wo);
        s->weight = fresnel_conductor(wo.z, c.eta, c.k);
        s->pdf = 1.0f;
        s->lobe = LOBE_REFLECTION | LOBE_DELTA;
        return 1;
    }
    float3 h = c.beckmann ? sample_beckmann_visible(wo, c.alpha, u.x, u.y) : sample_ggx_visible(wo, c.alpha, u.x, u.y);
    float wo_h = dot(wo, h);
    s->wi = 2.0f * wo_h * h - wo;
    if (s->wi.z <= 0.0f || wo_h <= 0.0f)
        return 0;
    s->pdf = metal_normal_pdf(c, wo, h) / (4.0f * wo_h);
    s->weight = fresnel_conductor(wo_h, c.eta, c.k) * metal_g1(c, s->wi, h);
    s->lobe = LOBE_GLOSSY | LOBE_REFLECTION;
    return s->pdf > 0.0f;
}
