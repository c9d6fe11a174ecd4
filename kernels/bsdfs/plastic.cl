/* plastic: a diffuse base under a smooth dielectric coating (Mitsuba 3's `plastic`, after
 * Weidlich & Wilkie, "Arbitrarily Layered Micro-Facet Surfaces", 2007). The coating reflects
 * specularly with the Fresnel reflectance F(cos_o); what it lets in reaches the base, is
 * scattered diffusely, bounces between base and coating, and leaves with 1 - F(cos_i):
 *     f(wo, wi) = rho / (pi eta^2) (1 - F(cos_o)) (1 - F(cos_i)),
 *     rho = rho_d / (1 - F_dr)            (linear)
 *     rho = rho_d / (1 - rho_d F_dr)      (nonlinear: the colour deepens with each bounce)
 * F_dr the coating's reflectance from inside averaged over the base's cosine-weighted light.
 *
 * Parameters (Material):
 *   p0.xyz  diffuse_reflectance, rho_d           p0.w  eta = int_ior / ext_ior
 *   p1.xyz  specular_reflectance, a factor on the coating's reflection
 *   p1.w    F_dr (computed on the host, app/materials/plastic.py)
 *   p2.x    the specular lobe's share in the lobe choice (mean specular over mean of both
 *           reflectances, scaled below by the Fresnel weights)
 *   p2.y    nonlinear (0 or 1)                   p2.z, p2.w  int_ior, ext_ior (the editor's)
 *
 * eval and pdf hold the diffuse part only; the coating's reflection is a delta. One-sided. */

float3 plastic_base(const global Material *m)
{
    float3 rho = m->p0.xyz;
    return m->p2.y != 0.0f ? rho / (1.0f - rho * m->p1.w) : rho / (1.0f - m->p1.w);
}

/* Fresnel reflectance of the coating seen from outside at cosine cos_theta. */
float plastic_fresnel(const global Material *m, float cos_theta)
{
    float cos_t, eta_ti;
    return fresnel_dielectric(cos_theta, m->p0.w, &cos_t, &eta_ti);
}

/* The probability of sampling the coating's reflection, given its Fresnel reflectance f_o. */
float plastic_specular_choice(const global Material *m, float f_o)
{
    float s = f_o * m->p2.x, d = (1.0f - f_o) * (1.0f - m->p2.x);
    return s + d > 0.0f ? s / (s + d) : 0.0f;
}

float3 eval_plastic(const global Material *m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    float t = (1.0f - plastic_fresnel(m, wo.z)) * (1.0f - plastic_fresnel(m, wi.z));
    return plastic_base(m) * (t / (PI_F * m->p0.w * m->p0.w));
}

float pdf_plastic(const global Material *m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    float p_s = plastic_specular_choice(m, plastic_fresnel(m, wo.z));
    return (1.0f - p_s) * pdf_cosine_hemisphere(wi.z);
}

int sample_plastic(const global Material *m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    float f_o = plastic_fresnel(m, wo.z);
    float p_s = plastic_specular_choice(m, f_o);
    if (u.x < p_s) {
        s->wi = reflect_local(wo);
        s->pdf = p_s;
        s->weight = m->p1.xyz * (f_o / p_s);
        s->lobe = LOBE_DELTA | LOBE_REFLECTION;
        return 1;
    }
    s->wi = sample_cosine_hemisphere(u.y, u.z);
    s->pdf = (1.0f - p_s) * pdf_cosine_hemisphere(s->wi.z);
    float t = (1.0f - f_o) * (1.0f - plastic_fresnel(m, s->wi.z));
    /* f cos / pdf: the cosine and 1/pi cancel against the cosine-weighted density */
    s->weight = plastic_base(m) * (t / (m->p0.w * m->p0.w * (1.0f - p_s)));
    s->lobe = LOBE_DIFFUSE | LOBE_REFLECTION;
    return s->pdf > 0.0f;
}
