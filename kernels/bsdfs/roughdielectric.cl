/* roughdielectric: a rough interface between two dielectrics, such as frosted or etched glass
 * (Mitsuba 3's `roughdielectric`; pbrt-v4's `dielectric` with a roughness): the microfacet
 * model of Walter et al. 2007 with the GGX or Beckmann distribution and Smith's separable
 * shadowing (kernels/interface.cl), its reflection times R and its transmission times T and the
 * (n_wo / n_wi)^2 by which radiance is compressed into a denser medium, as the smooth
 * dielectric's. Its parameters (a dielectric's, with alpha and alpha_v, the roughness along
 * the tangent and the bitangent, and distribution, 1 for Beckmann, 0 for GGX) are read through
 * ROUGHDIELECTRIC_<PARAM>, generated from their slots on the host (app/materials/dielectric.py).
 *
 * Transmissive: wo may lie on either side. Sampling draws a normal visible from wo (mirrored
 * to the outside when wo is inside, as Mitsuba 3 does), then reflects with the probability
 * F(wo.h) or refracts: the weight is R G1(wi, h), or T G1(wi, h) / e^2. Beckmann's code is
 * compiled only where a scene has it (BECKMANN). */

#ifdef BECKMANN
#define ROUGH_GLASS_IS_BECKMANN(m) (ROUGHDIELECTRIC_DISTRIBUTION(m) > 0.5f)
#else
#define ROUGH_GLASS_IS_BECKMANN(m) 0
#endif

Interface rough_glass(MaterialRef m)
{
    Interface c = {ROUGHDIELECTRIC_INT_IOR(m) / ROUGHDIELECTRIC_EXT_IOR(m),
                   (float2)(ROUGHDIELECTRIC_ALPHA(m), ROUGHDIELECTRIC_ALPHA_V(m)), ROUGH_GLASS_IS_BECKMANN(m)};
    return c;
}

float3 eval_roughdielectric(MaterialRef m, float3 wo, float3 wi)
{
    Interface c = rough_glass(m);
    float pdf;
    float f = eval_interface(c, wo, wi, LOBE_REFLECTION | LOBE_TRANSMISSION, &pdf);
    if (wo.z * wi.z > 0.0f)
        return ROUGHDIELECTRIC_SPECULAR_REFLECTANCE(m) * f;
    float e = wo.z > 0.0f ? c.eta : 1.0f / c.eta;          /* n(wi's side) / n(wo's side) */
    return ROUGHDIELECTRIC_SPECULAR_TRANSMITTANCE(m) * (f / (e * e));
}

float pdf_roughdielectric(MaterialRef m, float3 wo, float3 wi)
{
    float pdf;
    eval_interface(rough_glass(m), wo, wi, LOBE_REFLECTION | LOBE_TRANSMISSION, &pdf);
    return pdf;
}

int sample_roughdielectric(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (!sample_interface(rough_glass(m), wo, u, LOBE_REFLECTION | LOBE_TRANSMISSION, s))
        return 0;
    s->weight *= (s->lobe & LOBE_REFLECTION) ? ROUGHDIELECTRIC_SPECULAR_REFLECTANCE(m)
                                              : ROUGHDIELECTRIC_SPECULAR_TRANSMITTANCE(m) / (s->eta * s->eta);
    return 1;
}
