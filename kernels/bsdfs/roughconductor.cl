/* roughconductor: a rough metal, the GGX microfacet BRDF (kernels/microfacet.cl)
 *     f(wo, wi) = F(wo.h) D(h) G1(wo, h) G1(wi, h) / (4 cos(theta_o) cos(theta_i)),
 * h the half vector, F the conductor Fresnel reflectance (Mitsuba 3's `roughconductor` with
 * distribution ggx).
 *
 * Parameters (Material):
 *   p0.xyz  eta, the real part of the complex IOR     p0.w  alpha, the GGX roughness
 *   p1.xyz  k, its imaginary part
 *   p2.xyz  specular_reflectance, a factor on the reflectance
 *
 * Sampled by visible normals: the weight f cos / pdf is F(wo.h) G1(wi, h). One-sided. */

float3 eval_roughconductor(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    float alpha = m->p0.w;
    float3 h = unit(wo + wi);
    float g = ggx_g1(wo, h, alpha) * ggx_g1(wi, h, alpha);
    float3 f = fresnel_conductor(dot(wo, h), m->p0.xyz, m->p1.xyz);
    return m->p2.xyz * f * (ggx_d(h, alpha) * g / (4.0f * wo.z * wi.z));
}

/* pdf(wi) = D_wo(h) / (4 wo.h), the Jacobian of reflection (Walter et al. 2007, eq. 14) */
float pdf_roughconductor(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    float3 h = unit(wo + wi);
    float wo_h = dot(wo, h);
    return wo_h > 0.0f ? pdf_ggx_visible(wo, h, m->p0.w) / (4.0f * wo_h) : 0.0f;
}

int sample_roughconductor(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    float alpha = m->p0.w;
    float3 h = sample_ggx_visible(wo, alpha, u.y, u.z);
    float wo_h = dot(wo, h);
    s->wi = 2.0f * wo_h * h - wo;
    if (s->wi.z <= 0.0f || wo_h <= 0.0f)
        return 0;
    s->pdf = pdf_ggx_visible(wo, h, alpha) / (4.0f * wo_h);
    s->weight = m->p2.xyz * fresnel_conductor(wo_h, m->p0.xyz, m->p1.xyz) * ggx_g1(s->wi, h, alpha);
    s->lobe = LOBE_GLOSSY | LOBE_REFLECTION;
    return s->pdf > 0.0f;
}
