/* dielectric: a smooth interface between two dielectrics, such as the surface of a glass
 * object (Mitsuba 3's `dielectric`). Light is reflected with the Fresnel reflectance R and
 * refracted by Snell's law otherwise; beyond the critical angle it is totally reflected. Its
 * parameters (int_ior inside, opposite the normal; ext_ior outside; factors on reflection and
 * transmission) are read through DIELECTRIC_<PARAM>, generated from their slots on the host
 * (app/materials/dielectric.py).
 *
 * Transmissive: wo may lie on either side. Each lobe is chosen with its Fresnel weight (R or
 * 1 - R), so the weight is the factor alone, times (n_i / n_t)^2 for refraction: radiance is
 * compressed into a smaller solid angle on entering a denser medium (Veach 1997, section 5.2). */

int sample_dielectric(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    float cos_t, eta_ti;
    float r = fresnel_dielectric(wo.z, DIELECTRIC_INT_IOR(m) / DIELECTRIC_EXT_IOR(m), &cos_t, &eta_ti);
    if (u.y < r) {
        s->wi = reflect_local(wo);
        s->pdf = r;
        s->weight = DIELECTRIC_SPECULAR_REFLECTANCE(m);
        s->eta = 1.0f;
        s->lobe = LOBE_DELTA | LOBE_REFLECTION;
    } else {
        s->wi = (float3)(-eta_ti * wo.x, -eta_ti * wo.y, cos_t);
        s->pdf = 1.0f - r;
        s->weight = DIELECTRIC_SPECULAR_TRANSMITTANCE(m) * (eta_ti * eta_ti);
        s->eta = 1.0f / eta_ti;
        s->lobe = LOBE_DELTA | LOBE_TRANSMISSION;
    }
    return 1;
}
