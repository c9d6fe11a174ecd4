/* conductor: a smooth metal, a perfect mirror whose reflectance is the conductor Fresnel
 * equations' (Mitsuba 3's `conductor`).
 *
 * Parameters (Material):
 *   p0.xyz  eta, the real part of the complex IOR (relative to the outside), per channel
 *   p1.xyz  k, its imaginary part
 *   p2.xyz  specular_reflectance, a factor on the reflectance
 *
 * A delta BRDF (sample only: only sampling finds it). One-sided. */

int sample_conductor(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    s->wi = reflect_local(wo);
    s->pdf = 1.0f;
    s->weight = m->p2.xyz * fresnel_conductor(wo.z, m->p0.xyz, m->p1.xyz);
    s->lobe = LOBE_DELTA | LOBE_REFLECTION;
    return 1;
}
