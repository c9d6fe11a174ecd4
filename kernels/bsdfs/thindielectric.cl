/* thindielectric: a thin sheet of a dielectric, such as a window pane (Mitsuba 3's
 * `thindielectric`). Light is reflected, or passes straight through with no refraction (the
 * two faces' refractions cancel); the sheet's inner reflections are summed in closed form,
 * R' = R + T^2 R / (1 - R^2) = 2R / (1 + R), with R the Fresnel reflectance of one face. Its
 * parameters, a dielectric's, are read through THINDIELECTRIC_<PARAM>, generated from their
 * slots on the host (app/materials/dielectric.py).
 *
 * Transmissive and symmetric: both sides behave alike. */

int sample_thindielectric(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    float cos_t, eta_ti;
    float r = fresnel_dielectric(fabs(wo.z), THINDIELECTRIC_INT_IOR(m) / THINDIELECTRIC_EXT_IOR(m), &cos_t, &eta_ti);
    r = 2.0f * r / (1.0f + r);
    s->eta = 1.0f;
    if (u.y < r) {
        s->wi = reflect_local(wo);
        s->pdf = r;
        s->weight = THINDIELECTRIC_SPECULAR_REFLECTANCE(m);
        s->lobe = LOBE_DELTA | LOBE_REFLECTION;
    } else {
        s->wi = -wo;
        s->pdf = 1.0f - r;
        s->weight = THINDIELECTRIC_SPECULAR_TRANSMITTANCE(m);
        s->lobe = LOBE_DELTA | LOBE_TRANSMISSION;
    }
    return 1;
}
