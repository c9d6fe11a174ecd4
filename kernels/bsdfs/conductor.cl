/* conductor: a smooth metal, a perfect mirror whose reflectance is the conductor Fresnel
 * equations' (Mitsuba 3's `conductor`), of the complex IOR eta + i k relative to the outside
 * and a factor specular_reflectance, read through CONDUCTOR_ETA, _K and _SPECULAR_REFLECTANCE,
 * generated from their slots on the host (app/materials/conductor.py).
 *
 * A delta BRDF (sample only: only sampling finds it). One-sided. */

int sample_conductor(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    s->wi = reflect_local(wo);
    s->pdf = 1.0f;
    s->weight = CONDUCTOR_SPECULAR_REFLECTANCE(m) * fresnel_conductor(wo.z, CONDUCTOR_ETA(m), CONDUCTOR_K(m));
    s->lobe = LOBE_DELTA | LOBE_REFLECTION;
    return 1;
}
