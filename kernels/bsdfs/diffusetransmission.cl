/* diffusetransmission: Lambertian reflection and transmission (pbrt-v4's
 * `diffusetransmission`, for lampshades, curtains, leaves): f = R / pi towards wo's side of the
 * surface and T / pi through it, the same seen from either side. R and T are read through
 * DIFFUSETRANSMISSION_REFLECTANCE and _TRANSMITTANCE, generated from their slots on the host
 * (app/materials/diffusetransmission.py; app/materials/registry.py: tag_source).
 *
 * Sampled as pbrt-v4 samples it: reflection or transmission, chosen in proportion to the
 * largest channel of R and of T, then a cosine-distributed direction on that side. The
 * material is transmissive (MATERIAL_TRANSMISSIVE): wo may lie on either side. */

/* The probability of choosing reflection. */
float reflect_share(MaterialRef m)
{
    float3 r3 = DIFFUSETRANSMISSION_REFLECTANCE(m), t3 = DIFFUSETRANSMISSION_TRANSMITTANCE(m);
    float r = fmax(fmax(r3.x, r3.y), r3.z), t = fmax(fmax(t3.x, t3.y), t3.z);
    return r + t > 0.0f ? r / (r + t) : 1.0f;
}

float3 eval_diffusetransmission(MaterialRef m, float3 wo, float3 wi)
{
    float side = wo.z * wi.z;
    if (side == 0.0f)
        return (float3)(0.0f);
    return (side > 0.0f ? DIFFUSETRANSMISSION_REFLECTANCE(m) : DIFFUSETRANSMISSION_TRANSMITTANCE(m)) / PI_F;
}

float pdf_diffusetransmission(MaterialRef m, float3 wo, float3 wi)
{
    float side = wo.z * wi.z, share = reflect_share(m);
    if (side == 0.0f)
        return 0.0f;
    return (side > 0.0f ? share : 1.0f - share) * pdf_cosine_hemisphere(fabs(wi.z));
}

int sample_diffusetransmission(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z == 0.0f)
        return 0;
    float share = reflect_share(m);
    int reflect = u.x < share;
    float3 w = sample_cosine_hemisphere(u.y, u.z);
    /* w on wo's side to reflect, on the other to transmit */
    s->wi = (float3)(w.x, w.y, (reflect == (wo.z > 0.0f)) ? w.z : -w.z);
    float chosen = reflect ? share : 1.0f - share;
    s->pdf = chosen * pdf_cosine_hemisphere(w.z);
    s->weight = (reflect ? DIFFUSETRANSMISSION_REFLECTANCE(m) : DIFFUSETRANSMISSION_TRANSMITTANCE(m)) / chosen;      /* (X / pi) cos / (chosen cos / pi) */
    s->lobe = LOBE_DIFFUSE | (reflect ? LOBE_REFLECTION : LOBE_TRANSMISSION);
    return s->pdf > 0.0f;
}
