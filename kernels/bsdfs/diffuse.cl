/* diffuse: the Lambertian BRDF, f = rho_d / pi (Mitsuba 3's `diffuse`). Its parameter, rho_d
 * (the albedo), is read through DIFFUSE_RHO_D, generated from its slot on the host
 * (app/materials/basic.py: Diffuse; app/materials/registry.py: tag_source).
 *
 * Directions are in the local shading frame (z the normal); the surface is one-sided. */

float3 eval_diffuse(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    return DIFFUSE_RHO_D(m) / PI_F;
}

float pdf_diffuse(MaterialRef m, float3 wo, float3 wi)
{
    return wo.z > 0.0f ? pdf_cosine_hemisphere(wi.z) : 0.0f;
}

int sample_diffuse(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    s->wi = sample_cosine_hemisphere(u.y, u.z);
    s->pdf = pdf_cosine_hemisphere(s->wi.z);
    s->weight = DIFFUSE_RHO_D(m);       /* (rho_d / pi) cos / (cos / pi) */
    s->lobe = LOBE_DIFFUSE | LOBE_REFLECTION;
    return s->pdf > 0.0f;
}
