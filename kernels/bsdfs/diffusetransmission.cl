/* diffusetransmission: Lambertian reflection and transmission (pbrt-v4's
 * `diffusetransmission`, for lampshades, curtains, leaves): f = R / pi towards wo's side of the
 * surface and T / pi through it, the same seen from either side.
 *
 * Parameters (Material):
 *   p0.xyz  R, the reflectance, in [0, 1] per channel
 *   p1.xyz  T, the transmittance, in [0, 1] per channel (R + T <= 1 in each)
 *
 * Sampled as pbrt-v4 samples it: reflection or transmission, chosen in proportion to the
 * largest channel of R and of T, then a cosine-distributed direction on that side. The
 * material is transmissive (MATERIAL_TRANSMISSIVE): wo may lie on either side. */

/* The probability of choosing reflection. */
float reflect_share(MaterialRef m)
{
    float r = fmax(fmax(m->p0.x, m->p0.y), m->p0.z), t = fmax(fmax(m->p1.x, m->p1.y), m->p1.z);
    return r + t > 0.0f ? r / (r + t) : 1.0f;
}

float3 eval_diffusetransmission(MaterialRef m, float3 wo, float3 wi)
{
    float side = wo.z * wi.z;
    if (side == 0.0f)
        return (float3)(0.0f);
    return (side > 0.0f ? m->p0.xyz : m->p1.xyz) / PI_F;
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
    s->weight = (reflect ? m->p0.xyz : m->p1.xyz) / chosen;      /* (X / pi) cos / (chosen cos / pi) */
    s->lobe = LOBE_DIFFUSE | (reflect ? LOBE_REFLECTION : LOBE_TRANSMISSION);
    return s->pdf > 0.0f;
}
