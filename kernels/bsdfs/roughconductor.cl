/* roughconductor: a rough metal, the microfacet BRDF of a GGX or Beckmann distribution
 * (kernels/metal.cl; Mitsuba 3's `roughconductor`), times a specular_reflectance factor.
 *
 * Parameters (Material):
 *   p0.xyz  eta, the real part of the complex IOR     p0.w  alpha, the roughness along the tangent
 *   p1.xyz  k, its imaginary part                     p1.w  alpha_v, along the bitangent
 *   p2.xyz  specular_reflectance, a factor on the reflectance
 *                                                      p2.w  1 for Beckmann, 0 for GGX
 *
 * Sampled by visible normals of either distribution: the weight f cos / pdf is
 * F(wo.h) G1(wi, h). One-sided. Beckmann's code is compiled only into the programs of scenes
 * that have it (BECKMANN, app/materials/conductor.py): the branch cost scenes of GGX metals
 * 3-6 % on an H100. */

#ifdef BECKMANN
#define IS_BECKMANN(m) ((m)->p2.w > 0.5f)
#else
#define IS_BECKMANN(m) 0
#endif

Metal rough_metal(MaterialRef m)
{
    Metal c = {m->p0.xyz, m->p1.xyz, (float2)(m->p0.w, m->p1.w), IS_BECKMANN(m)};
    return c;
}

float3 eval_roughconductor(MaterialRef m, float3 wo, float3 wi)
{
    return m->p2.xyz * eval_metal(rough_metal(m), wo, wi);
}

float pdf_roughconductor(MaterialRef m, float3 wo, float3 wi)
{
    return pdf_metal(rough_metal(m), wo, wi);
}

int sample_roughconductor(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (!sample_metal(rough_metal(m), wo, u.yz, s))
        return 0;
    s->weight *= m->p2.xyz;
    return 1;
}
