/* thindielectric: a thin sheet of a dielectric, such as a window pane (Mitsuba 3's
 * `thindielectric`). Light is reflected, or passes straight through with no refraction (the
 * two faces' refractions cancel); the sheet's inner reflections are summed in closed form,
 * R' = R + T^2 R / (1 - R^2) = 2R / (1 + R), with R the Fresnel reflectance of one face.
 *
 * Parameters (Material):
 *   p0.x    int_ior, the sheet's IOR     p0.y  ext_ior, outside
 *   p1.xyz  specular_reflectance         p2.xyz  specular_transmittance
 *
 * Transmissive and symmetric: both sides behave alike. */

int sample_thindielectric(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    float cos_t, eta_ti;
    float r = fresnel_dielectric(fabs(wo.z), m->p0.x / m->p0.y, &cos_t, &eta_ti);
    r = 2.0f * r / (1.0f + r);
    s->eta = 1.0f;
    if (u.y < r) {
        s->wi = reflect_local(wo);
        s->pdf = r;
        s->weight = m->p1.xyz;
        s->lobe = LOBE_DELTA | LOBE_REFLECTION;
    } else {
        s->wi = -wo;
        s->pdf = 1.0f - r;
        s->weight = m->p2.xyz;
        s->lobe = LOBE_DELTA | LOBE_TRANSMISSION;
    }
    return 1;
}
