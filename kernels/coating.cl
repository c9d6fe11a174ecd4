/* A diffuse base under a dielectric coating, the layered model that plastic and roughplastic
 * share (Weidlich & Wilkie, "Arbitrarily Layered Micro-Facet Surfaces", 2007, as Mitsuba 3's
 * plastics). Light the coating lets in is scattered by the base, bounces between base and
 * coating, and leaves through the coating; the bounces sum to a geometric series.
 *
 * Both materials' rows are read through plastic's accessors, PLASTIC_<NAME>, generated from the
 * slots its host declares (app/materials/plastic.py), which roughplastic's extend: among them
 * PLASTIC_ETA = int_ior / ext_ior, PLASTIC_F_INT, the coating's reflectance seen from inside
 * averaged over the base's cosine-weighted light, and PLASTIC_SPECULAR_SHARE, the specular
 * lobe's share in the lobe choice (scaled below by the coating's reflection and transmission). */

/* The base's albedo after its bounces under the coating:
 *     rho / (1 - F_int)          (linear: the colour stays the one given)
 *     rho / (1 - rho F_int)      (nonlinear: it deepens with each bounce) */
float3 coated_base_albedo(MaterialRef m)
{
    float3 rho = PLASTIC_DIFFUSE_REFLECTANCE(m);
    return PLASTIC_NONLINEAR(m) != 0.0f ? rho / (1.0f - rho * PLASTIC_F_INT(m)) : rho / (1.0f - PLASTIC_F_INT(m));
}

/* The probability of sampling the coating's reflection, given the share r of the light at wo
 * that the coating reflects. */
float coating_choice(MaterialRef m, float r)
{
    float s = r * PLASTIC_SPECULAR_SHARE(m), d = (1.0f - r) * (1.0f - PLASTIC_SPECULAR_SHARE(m));
    return s + d > 0.0f ? s / (s + d) : 0.0f;
}

/* roughplastic's coating transmittance T(cos), tabulated at cos = (k / 15)^2, interpolated
 * linearly in sqrt(cos) (the table is dense at grazing angles). */
float lookup_cos_table(MaterialRef m, float cos_theta)
{
    float x = sqrt(clamp(cos_theta, 0.0f, 1.0f)) * 15.0f;
    int i = min((int)x, 14);
    return mix(ROUGHPLASTIC_TRANSMITTANCE(m)[i], ROUGHPLASTIC_TRANSMITTANCE(m)[i + 1], x - (float)i);
}
