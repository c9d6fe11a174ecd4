/* A diffuse base under a dielectric coating, the layered model that plastic and roughplastic
 * share (Weidlich & Wilkie, "Arbitrarily Layered Micro-Facet Surfaces", 2007, as Mitsuba 3's
 * plastics). Light the coating lets in is scattered by the base, bounces between base and
 * coating, and leaves through the coating; the bounces sum to a geometric series.
 *
 * Both materials pack (kernels/bsdfs/plastic.cl and roughplastic.cl):
 *   p0.xyz  diffuse_reflectance, rho_d           p0.w  eta = int_ior / ext_ior
 *   p1.xyz  specular_reflectance, a factor on the coating's reflection
 *   p1.w    F_int, the coating's reflectance seen from inside, averaged over the base's
 *           cosine-weighted light (computed on the host, app/materials/plastic.py)
 *   p2.x    the specular lobe's share in the lobe choice (mean specular over the mean of both
 *           reflectances, scaled below by the coating's reflection and transmission)
 *   p2.y    nonlinear (0 or 1)                   p2.z  ext_ior (the editor's) */

/* The base's albedo after its bounces under the coating:
 *     rho / (1 - F_int)          (linear: the colour stays the one given)
 *     rho / (1 - rho F_int)      (nonlinear: it deepens with each bounce) */
float3 coated_base_albedo(MaterialRef m)
{
    float3 rho = m->p0.xyz;
    return m->p2.y != 0.0f ? rho / (1.0f - rho * m->p1.w) : rho / (1.0f - m->p1.w);
}

/* The probability of sampling the coating's reflection, given the share r of the light at wo
 * that the coating reflects. */
float coating_choice(MaterialRef m, float r)
{
    float s = r * m->p2.x, d = (1.0f - r) * (1.0f - m->p2.x);
    return s + d > 0.0f ? s / (s + d) : 0.0f;
}

/* A function of cos(theta) tabulated in Material.table at cos = (k / 15)^2, interpolated
 * linearly in sqrt(cos) (the table is dense at grazing angles). */
float lookup_cos_table(MaterialRef m, float cos_theta)
{
    float x = sqrt(clamp(cos_theta, 0.0f, 1.0f)) * 15.0f;
    int i = min((int)x, 14);
    return mix(m->table[i], m->table[i + 1], x - (float)i);
}
