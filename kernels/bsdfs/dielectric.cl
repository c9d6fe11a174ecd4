/* dielectric: a smooth interface between two dielectrics, such as the surface of a glass
 * object (Mitsuba 3's `dielectric`). Light is reflected with the Fresnel reflectance R and
 * refracted by Snell's law otherwise; beyond the critical angle it is totally reflected.
 *
 * Parameters (Material):
 *   p0.x    int_ior, the IOR inside (opposite the normal)     p0.y  ext_ior, outside
 *   p1.xyz  specular_reflectance, a factor on reflection
 *   p2.xyz  specular_transmittance, a factor on transmission
 *
 * Transmissive: wo may lie on either side. Each lobe is chosen with its Fresnel weight (R or
 * 1 - R), so the weight is the factor alone, times (n_i / n_t)^2 for refraction: radiance is
 * compressed into a smaller solid angle on entering a denser medium (Veach 1997, section 5.2). */

int sample_dielectric(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    float cos_t, eta_ti;
    float r = fresnel_dielectric(wo.z, m->p0.x / m->p0.y, &cos_t, &eta_ti);
    if (u.y < r) {
        s->wi = reflect_local(wo);
        s->pdf = r;
        s->weight = m->p1.xyz;
        s->eta = 1.0f;
        s->lobe = LOBE_DELTA | LOBE_REFLECTION;
    } else {
        s->wi = (float3)(-eta_ti * wo.x, -eta_ti * wo.y, cos_t);
        s->pdf = 1.0f - r;
        s->weight = m->p2.xyz * (eta_ti * eta_ti);
        s->eta = 1.0f / eta_ti;
        s->lobe = LOBE_DELTA | LOBE_TRANSMISSION;
    }
    return 1;
}
