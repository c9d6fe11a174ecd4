/* plastic: a diffuse base under a smooth dielectric coating (Mitsuba 3's `plastic`; the layered
 * model of kernels/coating.cl). The coating reflects specularly with the Fresnel reflectance
 * F(cos_o); what it lets in reaches the base and leaves with 1 - F(cos_i):
 *     f(wo, wi) = rho' / (pi eta^2) (1 - F(cos_o)) (1 - F(cos_i)),
 * rho' the base's albedo after its bounces (coated_base_albedo).
 *
 * Parameters: those of kernels/coating.cl, PLASTIC_F_INT being the smooth coating's diffuse
 * Fresnel reflectance.
 *
 * eval and pdf hold the diffuse part only; the coating's reflection is a delta. One-sided. */

/* Fresnel reflectance of the coating seen from outside at cosine cos_theta. */
float plastic_fresnel(MaterialRef m, float cos_theta)
{
    float cos_t, eta_ti;
    return fresnel_dielectric(cos_theta, PLASTIC_ETA(m), &cos_t, &eta_ti);
}

float3 eval_plastic(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    float t = (1.0f - plastic_fresnel(m, wo.z)) * (1.0f - plastic_fresnel(m, wi.z));
    return coated_base_albedo(m) * (t / (PI_F * PLASTIC_ETA(m) * PLASTIC_ETA(m)));
}

float pdf_plastic(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    float p_s = coating_choice(m, plastic_fresnel(m, wo.z));
    return (1.0f - p_s) * pdf_cosine_hemisphere(wi.z);
}

int sample_plastic(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    float f_o = plastic_fresnel(m, wo.z);
    float p_s = coating_choice(m, f_o);
    if (u.x < p_s) {
        s->wi = reflect_local(wo);
        s->pdf = p_s;
        s->weight = PLASTIC_SPECULAR_REFLECTANCE(m) * (f_o / p_s);
        s->lobe = LOBE_DELTA | LOBE_REFLECTION;
        return 1;
    }
    s->wi = sample_cosine_hemisphere(u.y, u.z);
    s->pdf = (1.0f - p_s) * pdf_cosine_hemisphere(s->wi.z);
    float t = (1.0f - f_o) * (1.0f - plastic_fresnel(m, s->wi.z));
    /* f cos / pdf: the cosine and 1/pi cancel against the cosine-weighted density */
    s->weight = coated_base_albedo(m) * (t / (PLASTIC_ETA(m) * PLASTIC_ETA(m) * (1.0f - p_s)));
    s->lobe = LOBE_DIFFUSE | LOBE_REFLECTION;
    return s->pdf > 0.0f;
}
