/* roughconductor: a rough metal, the microfacet BRDF of a GGX or Beckmann distribution
 * (kernels/microfacet.cl)
 *     f(wo, wi) = F(wo.h) D(h) G1(wo, h) G1(wi, h) / (4 cos(theta_o) cos(theta_i)),
 * h the half vector, F the conductor Fresnel reflectance (Mitsuba 3's `roughconductor`). Its
 * parameters (eta + i k, the complex IOR; alpha and alpha_v, the roughness along the tangent
 * and the bitangent; specular_reflectance; distribution, 1 for Beckmann, 0 for GGX) are read
 * through ROUGHCONDUCTOR_<PARAM>, generated from their slots on the host
 * (app/materials/conductor.py), and so are a coatedconductor's base's, in the same slots.
 *
 * Sampled by visible normals of either distribution: the weight f cos / pdf is
 * F(wo.h) G1(wi, h). One-sided. Beckmann's code is compiled only into the programs of scenes
 * that have it (BECKMANN, app/materials/conductor.py): as a branch it cost scenes of GGX metals
 * time (docs/notes/performance-2026-11.md, 2026-11-24: Beckmann microfacets). */

#ifdef BECKMANN
#define IS_BECKMANN(m) (ROUGHCONDUCTOR_DISTRIBUTION(m) > 0.5f)
#else
#define IS_BECKMANN(m) 0
#endif

#define CONDUCTOR_ALPHA(m) ((float2)(ROUGHCONDUCTOR_ALPHA(m), ROUGHCONDUCTOR_ALPHA_V(m)))

float conductor_d(MaterialRef m, float3 h)
{
    return IS_BECKMANN(m) ? beckmann_d(h, CONDUCTOR_ALPHA(m)) : ggx_d(h, CONDUCTOR_ALPHA(m));
}

float conductor_g1(MaterialRef m, float3 v, float3 h)
{
    return IS_BECKMANN(m) ? beckmann_g1(v, h, CONDUCTOR_ALPHA(m)) : ggx_g1(v, h, CONDUCTOR_ALPHA(m));
}

/* The density, per solid angle of h, of the normal that sampling draws from wo */
float pdf_conductor_normal(MaterialRef m, float3 wo, float3 h)
{
    return IS_BECKMANN(m) ? pdf_beckmann_visible(wo, h, CONDUCTOR_ALPHA(m)) : pdf_ggx_visible(wo, h, CONDUCTOR_ALPHA(m));
}

/* f of the metal seen from a medium of IOR n_outside (1: air): the Fresnel term takes the
 * metal's eta and k relative to that medium, as pbrt-v4 divides them by the coating's IOR under
 * a coating (CoatedConductorMaterial::GetBxDF, materials.cpp: ce /= ieta; ck /= ieta). */
float3 eval_rough_metal(MaterialRef m, float n_outside, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    float3 h = unit(wo + wi);
    float g = conductor_g1(m, wo, h) * conductor_g1(m, wi, h);
    float3 f = fresnel_conductor(dot(wo, h), ROUGHCONDUCTOR_ETA(m) / n_outside, ROUGHCONDUCTOR_K(m) / n_outside);
    return ROUGHCONDUCTOR_SPECULAR_REFLECTANCE(m) * f * (conductor_d(m, h) * g / (4.0f * wo.z * wi.z));
}

float3 eval_roughconductor(MaterialRef m, float3 wo, float3 wi)
{
    return eval_rough_metal(m, 1.0f, wo, wi);
}

/* pdf(wi) = pdf(h) / (4 wo.h), the Jacobian of reflection (Walter et al. 2007, eq. 14) */
float pdf_roughconductor(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    float3 h = unit(wo + wi);
    float wo_h = dot(wo, h);
    return wo_h > 0.0f ? pdf_conductor_normal(m, wo, h) / (4.0f * wo_h) : 0.0f;
}

/* A sample of the metal seen from a medium of IOR n_outside (eval_rough_metal) */
int sample_rough_metal(MaterialRef m, float n_outside, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    float2 alpha = CONDUCTOR_ALPHA(m);
    float3 h = IS_BECKMANN(m) ? sample_beckmann_visible(wo, alpha, u.y, u.z)
                              : sample_ggx_visible(wo, alpha, u.y, u.z);
    float wo_h = dot(wo, h);
    s->wi = 2.0f * wo_h * h - wo;
    if (s->wi.z <= 0.0f || wo_h <= 0.0f)
        return 0;
    s->pdf = pdf_conductor_normal(m, wo, h) / (4.0f * wo_h);
    s->weight = ROUGHCONDUCTOR_SPECULAR_REFLECTANCE(m) * fresnel_conductor(wo_h, ROUGHCONDUCTOR_ETA(m) / n_outside,
                                                                  ROUGHCONDUCTOR_K(m) / n_outside)
                * conductor_g1(m, s->wi, h);
    s->lobe = LOBE_GLOSSY | LOBE_REFLECTION;
    return s->pdf > 0.0f;
}

int sample_roughconductor(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    return sample_rough_metal(m, 1.0f, wo, u, s);
}
