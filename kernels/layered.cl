/* pbrt-v4's layered BSDFs (`coateddiffuse`, `coatedconductor`): a base (Lambertian, or a metal:
 * a roughconductor's row, kernels/bsdfs/roughconductor.cl, or a mirror) under a dielectric coating (smooth, or rough with GGX microfacets:
 * kernels/interface.cl), with a layer of homogeneous medium between them: the layered BSDF of
 * Guo, Hasan and Zhao, "Position-Free Monte Carlo Simulation for Arbitrary Layered BSDFs",
 * SIGGRAPH Asia 2018, as pbrt-v4's LayeredBxDF estimates it. Light is followed on a random walk
 * between the two interfaces, through the layer (transmittance exp(-dz / |cos|), its extinction
 * 1 per unit of thickness; scattering by a Henyey-Greenstein phase function where the albedo is
 * not 0), at most max_depth events:
 *   eval_layers    an unbiased estimate of f: the walk from wo, with next-event estimation
 *                  towards wi (through a direction into the layer sampled from wi) weighed by
 *                  MIS;
 *   pdf_layers     an estimate of the density that sample_layers draws with, mixed with
 *                  1 / (4 pi);
 *   sample_layers  the walk itself, whose weight is the path's f cos / pdf; a walk whose every
 *                  event was a delta (a smooth coating over a mirror) is a delta sample.
 * Both estimates draw their random numbers from a hash of the two directions (of wo and the
 * uniforms for sample), as pbrt-v4 seeds its RNG: an evaluation is a deterministic function of
 * its arguments. Light sampling and BSDF sampling do not see bitwise the same directions (one
 * passes a direction through the shading frame and back), so their pdf estimates are
 * independent; MIS stays unbiased because each estimate's expectation is the density both
 * strategies sample, the argument pbrt-v4 relies on too. One-sided here (pbrt's are two-sided: app/scene/pbrt gives them `twosided`).
 *
 * Transmission through the coating is radiance's when the walk enters it from wo and leaves it
 * towards wi (divided by (n_t / n_i)^2), importance's (not divided) for the direction sampled
 * from wi, as pbrt-v4's TransportMode has it; the two factors of a path cancel. */

#define LAYER_PDF_UNIFORM 0.1f     /* the share of 1 / (4 pi) in pdf's estimate (pbrt-v4's) */

typedef struct {
    Interface top;       /* the coating */
    int metal;           /* the base: 1 the metal of `base`, a coatedconductor's row read as a
                            roughconductor's (conductor_alpha 0: a mirror), 0 Lambertian of
                            reflectance `rho` */
    MaterialRef base;
    float3 rho;
    float3 albedo;       /* the layer's single-scattering albedo (0: it only absorbs) */
    float thickness;
    float g;             /* its phase function's mean cosine */
    int max_depth;       /* events per walk */
    int samples;         /* walks per estimate */
} Layers;

/* The base, seen in the layer's frame with both directions above it; a metal seen from inside
 * the coating, its eta and k relative to the coating's IOR (eval_rough_metal) */
int base_is_delta(const Layers *l)
{
    return l->metal && COATEDCONDUCTOR_CONDUCTOR_ALPHA(l->base) == 0.0f;
}

float3 eval_base(const Layers *l, float3 wo, float3 wi)
{
    if (l->metal)
        return base_is_delta(l) ? (float3)(0.0f) : eval_rough_metal(l->base, l->top.eta, wo, wi);
    return wo.z > 0.0f && wi.z > 0.0f ? l->rho * (1.0f / PI_F) : (float3)(0.0f);
}

float pdf_base(const Layers *l, float3 wo, float3 wi)
{
    if (l->metal)
        return base_is_delta(l) ? 0.0f : pdf_roughconductor(l->base, wo, wi);
    return wo.z > 0.0f ? pdf_cosine_hemisphere(wi.z) : 0.0f;
}

int sample_base(const Layers *l, float3 wo, float2 u, BSDFSample *s)
{
    if (base_is_delta(l)) {                     /* a mirror */
        s->wi = reflect_local(wo);
        s->weight = fresnel_conductor(wo.z, COATEDCONDUCTOR_ETA(l->base) / l->top.eta, COATEDCONDUCTOR_K(l->base) / l->top.eta);
        s->pdf = 1.0f;
        s->eta = 1.0f;
        s->lobe = LOBE_REFLECTION | LOBE_DELTA;
        return wo.z > 0.0f;
    }
    if (l->metal) {
        s->eta = 1.0f;
        return sample_rough_metal(l->base, l->top.eta, wo, (float3)(0.0f, u.x, u.y), s);
    }
    s->wi = sample_cosine_hemisphere(u.x, u.y);
    s->pdf = pdf_cosine_hemisphere(s->wi.z);
    s->weight = l->rho;
    s->eta = 1.0f;
    s->lobe = LOBE_DIFFUSE | LOBE_REFLECTION;
    return wo.z > 0.0f && s->pdf > 0.0f;
}

/* A stream of uniforms hashed from two vectors' bits (and a salt telling the uses apart). */
Rng layer_rng(float3 a, float3 b, uint salt)
{
    Rng r;
    r.key = pcg4d(as_uint4((float4)(a, 0.0f)) ^ (uint4)(salt)) ^ pcg4d(as_uint4((float4)(b, 1.0f)));
    r.dim = 0u;
    return r;
}

/* Transmittance through the layer over a height dz along w. */
float layer_transmittance(float dz, float3 w)
{
    return fabs(dz) <= FLT_MIN ? 1.0f : exp(-fabs(dz / w.z));
}

/* Radiance's transmission weight through the coating: the sample's, over (n_t / n_i)^2. */
float3 radiance_weight(const BSDFSample *s)
{
    return (s->lobe & LOBE_TRANSMISSION) ? s->weight / (s->eta * s->eta) : s->weight;
}

/* Radiance's transmission out through a rough coating, from direction w inside (going up) to
 * wi, for a walk that sampled w with density w_pdf (0: by a delta, which no other technique
 * finds), weighed against the technique that samples the same inside direction from wi (its
 * density: the coating's towards -w from wi). pbrt-v4
 * weighs it against the coating's density of wi from -w instead, whose weights and the other
 * technique's do not sum to 1: that estimated 5-10 % more than the walk samples for roughness
 * 0.1-0.5 (tests/test_bsdfs.py: sampling against the quadrature of eval). */
float exit_through_coating(Interface top, float3 w, float3 wi, float w_pdf)
{
    float pdf, from_wi;
    float f = eval_interface(top, -w, wi, LOBE_TRANSMISSION, &pdf);
    eval_interface(top, wi, -w, LOBE_TRANSMISSION, &from_wi);
    float wt = w_pdf > 0.0f ? mis_weight(w_pdf, from_wi) : 1.0f;
    return f * top.eta * top.eta * wt;     /* (n_i / n_t)^2 = eta^2 */
}

/* Directions into the layer through the coating, from wo (radiance's: 0 when it has none) and
 * from wi (the virtual light's, importance's: is->pdf 0 when it has none, and the walk goes
 * on without the estimates that need it, where pbrt-v4 gives the whole walk up; with a rough
 * coating, whose sampled normal may refract wi nowhere, that lost up to 3 % of f). */
int enter_layer(Interface top, float3 wo, float3 wi, Rng *rng, BSDFSample *os, BSDFSample *is)
{
    os->eta = is->eta = 1.0f;
    int entered = sample_interface(top, wo, next_uniform4(rng).xyz, LOBE_TRANSMISSION, os);
    if (!sample_interface(top, wi, next_uniform4(rng).xyz, LOBE_TRANSMISSION, is))
        is->pdf = 0.0f;
    return entered;
}

/* Russian roulette once a walk carries little (pbrt-v4's rule), from uniform u: 0 ends it. */
int walk_survives(float3 *beta, int depth, float u)
{
    float most = fmax(fmax(beta->x, beta->y), beta->z);
    if (depth > 3 && most < 0.25f) {
        float q = fmax(0.0f, 1.0f - most);
        if (u < q)
            return 0;
        *beta /= 1.0f - q;
    }
    return 1;
}

float3 eval_layers(const Layers *l, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    Interface top = l->top;
    int rough = !is_smooth(top), base_delta = base_is_delta(l);
    float pdf;
    float3 f = (float3)(l->samples * eval_interface(top, wo, wi, LOBE_REFLECTION, &pdf));
    Rng rng = layer_rng(wo, wi, 1u);
    for (int k = 0; k < l->samples; ++k) {
        BSDFSample os, is;
        if (!enter_layer(top, wo, wi, &rng, &os, &is))
            continue;
        int light = is.pdf > 0.0f;                    /* a direction from wi to estimate with */
        float3 is_f = light ? is.weight / fabs(is.wi.z) : (float3)(0.0f);   /* its f / pdf */
        float3 beta = radiance_weight(&os);
        float z = l->thickness;
        float3 w = os.wi;
        for (int depth = 0; depth < l->max_depth; ++depth) {
            float4 u = next_uniform4(&rng);
            if (!walk_survives(&beta, depth, u.w))
                break;
            if (all(l->albedo == 0.0f)) {
                z = z == l->thickness ? 0.0f : l->thickness;
                beta *= layer_transmittance(l->thickness, w);
            } else {
                float zp = z + copysign(-log1p(-u.x) * fabs(w.z), w.z);
                if (zp == z)
                    continue;
                if (0.0f < zp && zp < l->thickness) {
                    /* scattered inside the layer: light through the top along the direction
                       sampled from wi, weighed against phase sampling */
                    if (light) {
                        float phase = eval_hg(l->g, -w, -is.wi);
                        float wt = rough ? mis_weight(is.pdf, phase) : 1.0f;
                        f += beta * l->albedo * phase * wt * layer_transmittance(zp - l->thickness, is.wi) * is_f;
                    }
                    float phase_pdf;
                    float3 next = sample_hg(l->g, -w, next_uniform4(&rng).xy, &phase_pdf);
                    if (!(phase_pdf > 0.0f) || next.z == 0.0f)
                        continue;
                    beta *= l->albedo;
                    w = next;
                    z = zp;
                    if (rough && z < l->thickness && w.z > 0.0f)
                        f += beta * layer_transmittance(zp - l->thickness, w) * exit_through_coating(top, w, wi, phase_pdf);
                    continue;
                }
                z = clamp(zp, 0.0f, l->thickness);
            }
            if (z == l->thickness) {
                /* reflected back down by the coating */
                BSDFSample bs;
                bs.eta = 1.0f;
                if (!sample_interface(top, -w, next_uniform4(&rng).xyz, LOBE_REFLECTION, &bs))
                    break;
                beta *= bs.weight;
                w = bs.wi;
            } else {
                /* the base: light through the top along the direction sampled from wi ... */
                if (!base_delta && light) {
                    float wt = rough ? mis_weight(is.pdf, pdf_base(l, -w, -is.wi)) : 1.0f;
                    f += beta * eval_base(l, -w, -is.wi) * fabs(is.wi.z) * wt
                         * layer_transmittance(l->thickness, is.wi) * is_f;
                }
                /* ... and a bounce off it, with light through the top along it */
                BSDFSample bs;
                if (!sample_base(l, -w, next_uniform4(&rng).xy, &bs))
                    break;
                beta *= bs.weight;
                w = bs.wi;
                if (rough)
                    f += beta * layer_transmittance(l->thickness, w)
                         * exit_through_coating(top, w, wi, base_delta ? 0.0f : bs.pdf);
            }
        }
    }
    return f / l->samples;
}

float pdf_layers(const Layers *l, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    Interface top = l->top;
    float pdf;
    eval_interface(top, wo, wi, LOBE_REFLECTION, &pdf);
    float sum = l->samples * pdf;
    Rng rng = layer_rng(wi, wo, 2u);
    for (int k = 0; k < l->samples; ++k) {
        /* the density of the path top-transmission, base reflection, top-transmission */
        BSDFSample os, is;
        if (!enter_layer(top, wo, wi, &rng, &os, &is))
            continue;
        if (is_smooth(top)) {
            sum += is.pdf > 0.0f ? pdf_base(l, -os.wi, -is.wi) : 0.0f;
            continue;
        }
        /* by MIS of the base's density towards -is.wi and the top's towards wi after a
           bounce off the base */
        BSDFSample rs;
        if (!sample_base(l, -os.wi, next_uniform4(&rng).xy, &rs))
            continue;
        float t_pdf;
        eval_interface(top, -rs.wi, wi, LOBE_REFLECTION | LOBE_TRANSMISSION, &t_pdf);
        if (base_is_delta(l)) {
            sum += t_pdf;
            continue;
        }
        float r_pdf = is.pdf > 0.0f ? pdf_base(l, -os.wi, -is.wi) : 0.0f;
        sum += mis_weight(is.pdf, r_pdf) * r_pdf + mis_weight(rs.pdf, t_pdf) * t_pdf;
    }
    return mix(1.0f / (4.0f * PI_F), sum / l->samples, 1.0f - LAYER_PDF_UNIFORM);
}

int sample_layers(const Layers *l, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    Interface top = l->top;
    if (!sample_interface(top, wo, u, LOBE_REFLECTION | LOBE_TRANSMISSION, s))
        return 0;
    if (s->lobe & LOBE_REFLECTION) {
        /* the coating's own reflection: the sample as it is (a delta where it is smooth) */
        if (!is_smooth(top))
            s->pdf = pdf_layers(l, wo, s->wi);
        return 1;
    }
    Rng rng = layer_rng(wo, u, 3u);
    float3 beta = radiance_weight(s);
    float3 w = s->wi;
    float z = l->thickness;
    int specular = (s->lobe & LOBE_DELTA) != 0;
    for (int depth = 0; depth < l->max_depth; ++depth) {
        float4 v = next_uniform4(&rng);
        if (!walk_survives(&beta, depth, v.w))
            return 0;
        if (any(l->albedo != 0.0f)) {
            float zp = z + copysign(-log1p(-v.x) * fabs(w.z), w.z);
            if (zp == z)
                return 0;
            if (0.0f < zp && zp < l->thickness) {
                float phase_pdf;
                float3 next = sample_hg(l->g, -w, (float2)(v.y, v.z), &phase_pdf);
                if (!(phase_pdf > 0.0f) || next.z == 0.0f)
                    return 0;
                beta *= l->albedo;
                w = next;
                z = zp;
                specular = 0;
                continue;
            }
            z = clamp(zp, 0.0f, l->thickness);
        } else {
            z = z == l->thickness ? 0.0f : l->thickness;
            beta *= layer_transmittance(l->thickness, w);
        }
        BSDFSample bs;
        bs.eta = 1.0f;
        if (z == l->thickness) {
            if (!sample_interface(top, -w, next_uniform4(&rng).xyz, LOBE_REFLECTION | LOBE_TRANSMISSION, &bs))
                return 0;
            beta *= radiance_weight(&bs);
            w = bs.wi;
            specular &= (bs.lobe & LOBE_DELTA) != 0;
            if (bs.lobe & LOBE_TRANSMISSION) {
                /* out of the layers: the walk's weight, and for MIS the estimated density (a
                   walk of deltas alone is a delta: no other technique finds it) */
                s->wi = w;
                s->weight = beta;
                s->eta = 1.0f;
                s->lobe = LOBE_REFLECTION | (specular ? LOBE_DELTA : LOBE_GLOSSY);
                s->pdf = specular ? 1.0f : pdf_layers(l, wo, w);
                return s->pdf > 0.0f;
            }
        } else {
            if (!sample_base(l, -w, next_uniform4(&rng).xy, &bs))
                return 0;
            beta *= bs.weight;
            w = bs.wi;
            specular &= (bs.lobe & LOBE_DELTA) != 0;
        }
    }
    return 0;
}

/* The eval, pdf and sample of BSDF `name` (kernels/bsdf.cl) as the layers that function
 * `layers_of` reads from its material. */
#define LAYERED_BSDF(name, layers_of)                                                          \
    float3 eval_##name(MaterialRef m, float3 wo, float3 wi)                                    \
    {                                                                                          \
        Layers l = layers_of(m);                                                               \
        return eval_layers(&l, wo, wi);                                                        \
    }                                                                                          \
    float pdf_##name(MaterialRef m, float3 wo, float3 wi)                                      \
    {                                                                                          \
        Layers l = layers_of(m);                                                               \
        return pdf_layers(&l, wo, wi);                                                         \
    }                                                                                          \
    int sample_##name(MaterialRef m, float3 wo, float3 u, BSDFSample *s)                       \
    {                                                                                          \
        Layers l = layers_of(m);                                                               \
        return sample_layers(&l, wo, u, s);                                                    \
    }
