/* roughplastic: a diffuse base under a rough dielectric coating (Mitsuba 3's `roughplastic`;
 * the layered model of kernels/coating.cl). The coating reflects as a GGX or Beckmann
 * microfacet interface; the base's light passes it twice, scaled each time by the rough
 * interface's transmittance T (1 minus its directional albedo, tabulated on the host):
 *     f(wo, wi) = spec F(wo.h) D(h) G1(wo, h) G1(wi, h) / (4 cos_o cos_i)
 *               + rho' / (pi eta^2) T(cos_o) T(cos_i),
 * rho' the base's albedo after its bounces (coated_base_albedo).
 *
 * Parameters: those of kernels/coating.cl, PLASTIC_F_INT being the rough coating's mean
 * internal reflectance, and ROUGHPLASTIC_SIGNED_ALPHA, alpha negated for Beckmann (compiled in
 * only where a scene has it: BECKMANN), and ROUGHPLASTIC_TRANSMITTANCE, T(cos) from outside
 * (app/materials/plastic.py: RoughPlastic).
 *
 * The lobe is chosen as Mitsuba does, from the tabulated reflectance 1 - T(cos_o); eval and pdf
 * hold both lobes, so a sample's weight is f cos / pdf of the whole. One-sided. */

#ifdef BECKMANN
#define PLASTIC_IS_BECKMANN(m) (ROUGHPLASTIC_SIGNED_ALPHA(m) < 0.0f)
#else
#define PLASTIC_IS_BECKMANN(m) 0
#endif

/* The coating as an interface of kernels/interface.cl */
Interface plastic_coating(MaterialRef m)
{
    Interface c = {PLASTIC_ETA(m), (float2)(fabs(ROUGHPLASTIC_SIGNED_ALPHA(m))), PLASTIC_IS_BECKMANN(m)};
    return c;
}

float3 eval_roughplastic(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    Interface c = plastic_coating(m);
    float eta = PLASTIC_ETA(m);
    float3 h = unit(wo + wi);
    float cos_t, eta_ti;
    float f = fresnel_dielectric(dot(wo, h), eta, &cos_t, &eta_ti);
    float g = interface_g1(c, wo, h) * interface_g1(c, wi, h);
    float3 specular = PLASTIC_SPECULAR_REFLECTANCE(m) * (f * interface_d(c, h) * g / (4.0f * wo.z * wi.z));
    float t = lookup_cos_table(m, wo.z) * lookup_cos_table(m, wi.z);
    return specular + coated_base_albedo(m) * (t / (PI_F * eta * eta));
}

/* The lobe choice's mixture: D_wo(h) / (4 wo.h) for the coating (Walter et al. 2007, eq. 14),
 * the cosine-weighted hemisphere for the base. */
float pdf_roughplastic(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    float p_s = coating_choice(m, 1.0f - lookup_cos_table(m, wo.z));
    float3 h = unit(wo + wi);
    float wo_h = dot(wo, h);
    float specular = wo_h > 0.0f ? interface_normal_pdf(plastic_coating(m), wo, h) / (4.0f * wo_h) : 0.0f;
    return p_s * specular + (1.0f - p_s) * pdf_cosine_hemisphere(wi.z);
}

int sample_roughplastic(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    float p_s = coating_choice(m, 1.0f - lookup_cos_table(m, wo.z));
    int specular = u.x < p_s;
    if (specular) {
        Interface c = plastic_coating(m);
        float3 h = c.beckmann ? sample_beckmann_visible(wo, c.alpha, u.y, u.z) : sample_ggx_visible(wo, c.alpha, u.y, u.z);
        s->wi = 2.0f * dot(wo, h) * h - wo;
    } else {
        s->wi = sample_cosine_hemisphere(u.y, u.z);
    }
    s->pdf = pdf_roughplastic(m, wo, s->wi);
    if (s->pdf <= 0.0f)
        return 0;
    s->weight = eval_roughplastic(m, wo, s->wi) * (s->wi.z / s->pdf);
    s->lobe = (specular ? LOBE_GLOSSY : LOBE_DIFFUSE) | LOBE_REFLECTION;
    return 1;
}
