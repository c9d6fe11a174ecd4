/* coateddiffuse: pbrt-v4's `coateddiffuse`, a Lambertian base under a dielectric coating
 * (smooth, or rough with GGX microfacets: kernels/interface.cl), with a layer of homogeneous
 * medium between them: the layered BSDF of Guo, Hasan and Zhao, "Position-Free Monte Carlo
 * Simulation for Arbitrary Layered BSDFs", SIGGRAPH Asia 2018, as pbrt-v4's LayeredBxDF
 * estimates it. Light is followed on a random walk between the two interfaces, through the
 * layer (transmittance exp(-dz / |cos|), its extinction 1 per unit of thickness; scattering by a
 * Henyey-Greenstein phase function where the albedo is not 0), at most maxdepth events:
 *   eval  an unbiased estimate of f: the walk from wo, with next-event estimation towards wi
 *         (through a direction into the layer sampled from wi) weighed by MIS;
 *   pdf   an estimate of the density that sample draws with, mixed with 1 / (4 pi);
 *   sample  the walk itself, whose weight is the path's f cos / pdf.
 * Both estimates draw their random numbers from a hash of the two directions (of wo and the
 * uniforms for sample), as pbrt-v4 seeds its RNG: an evaluation is a deterministic function of
 * its arguments, so light sampling and BSDF sampling see the same pdf and their MIS weights sum
 * to 1. One-sided here (pbrt's is two-sided: app/scene/pbrt gives it `twosided`).
 *
 * Parameters (Material):
 *   p0.xyz  reflectance of the base                        p0.w  the coating's alpha (0: smooth)
 *   p1.x    eta, the coating's IOR                         p1.y  thickness of the layer
 *   p1.z    g of the layer's phase function                p1.w  maxdepth, events per walk
 *   p2.xyz  albedo of the layer's medium (0: it absorbs)   p2.w  nsamples, walks per estimate
 *
 * Transmission through the coating is radiance's when the walk enters it from wo and leaves it
 * towards wi (divided by (n_t / n_i)^2), importance's (not divided) for the direction sampled
 * from wi, as pbrt-v4's TransportMode has it; the two factors of a path cancel. */

#define LAYER_PDF_UNIFORM 0.1f     /* the share of 1 / (4 pi) in pdf's estimate (pbrt-v4's) */

Interface coating_of(MaterialRef m)
{
    Interface c = {m->p1.x, (float2)(m->p0.w), 0};
    return c;
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
 * wi, for a walk that sampled w with density w_pdf, weighed against the technique that samples
 * the same inside direction from wi (its density: the coating's towards -w from wi). pbrt-v4
 * weighs it against the coating's density of wi from -w instead, whose weights and the other
 * technique's do not sum to 1: that estimated 5-10 % more than the walk samples for roughness
 * 0.1-0.5 (tests/test_materials.py). */
float exit_through_coating(Interface top, float3 w, float3 wi, float w_pdf)
{
    float pdf, from_wi;
    float f = eval_interface(top, -w, wi, LOBE_TRANSMISSION, &pdf);
    eval_interface(top, wi, -w, LOBE_TRANSMISSION, &from_wi);
    return f * top.eta * top.eta * mis_weight(w_pdf, from_wi);     /* (n_i / n_t)^2 = eta^2 */
}

/* Directions into the layer through the coating, from wo (radiance's) and from wi (the
 * virtual light's, importance's); 0 when either has none. */
int enter_layer(Interface top, float3 wo, float3 wi, Rng *rng, BSDFSample *os, BSDFSample *is)
{
    os->eta = is->eta = 1.0f;
    return sample_interface(top, wo, next_uniform4(rng).xyz, LOBE_TRANSMISSION, os)
           && sample_interface(top, wi, next_uniform4(rng).xyz, LOBE_TRANSMISSION, is);
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

float3 eval_coateddiffuse(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return (float3)(0.0f);
    Interface top = coating_of(m);
    float3 rho = m->p0.xyz, albedo = m->p2.xyz;
    float thickness = m->p1.y, g = m->p1.z;
    int max_depth = (int)m->p1.w, samples = (int)m->p2.w;
    int rough = !is_smooth(top);
    float pdf;
    float3 f = (float3)(samples * eval_interface(top, wo, wi, LOBE_REFLECTION, &pdf));
    Rng rng = layer_rng(wo, wi, 1u);
    for (int k = 0; k < samples; ++k) {
        BSDFSample os, is;
        if (!enter_layer(top, wo, wi, &rng, &os, &is))
            continue;
        float3 is_f = is.weight / fabs(is.wi.z);      /* f / pdf of the direction from wi */
        float3 beta = radiance_weight(&os);
        float z = thickness;
        float3 w = os.wi;
        for (int depth = 0; depth < max_depth; ++depth) {
            float4 u = next_uniform4(&rng);
            if (!walk_survives(&beta, depth, u.w))
                break;
            if (all(albedo == 0.0f)) {
                z = z == thickness ? 0.0f : thickness;
                beta *= layer_transmittance(thickness, w);
            } else {
                float zp = z + copysign(-log1p(-u.x) * fabs(w.z), w.z);
                if (zp == z)
                    continue;
                if (0.0f < zp && zp < thickness) {
                    /* scattered inside the layer: light through the top along the direction
                       sampled from wi, weighed against phase sampling */
                    float phase = eval_hg(g, -w, -is.wi);
                    float wt = rough ? mis_weight(is.pdf, phase) : 1.0f;
                    f += beta * albedo * phase * wt * layer_transmittance(zp - thickness, is.wi) * is_f;
                    float phase_pdf;
                    float3 next = sample_hg(g, -w, next_uniform4(&rng).xy, &phase_pdf);
                    if (!(phase_pdf > 0.0f) || next.z == 0.0f)
                        continue;
                    beta *= albedo;
                    w = next;
                    z = zp;
                    if (rough && z < thickness && w.z > 0.0f)
                        f += beta * layer_transmittance(zp - thickness, w) * exit_through_coating(top, w, wi, phase_pdf);
                    continue;
                }
                z = clamp(zp, 0.0f, thickness);
            }
            if (z == thickness) {
                /* reflected back down by the coating */
                BSDFSample bs;
                bs.eta = 1.0f;
                if (!sample_interface(top, -w, next_uniform4(&rng).xyz, LOBE_REFLECTION, &bs))
                    break;
                beta *= bs.weight;
                w = bs.wi;
            } else {
                /* the base: light through the top along the direction sampled from wi ... */
                float base_pdf = pdf_cosine_hemisphere(-is.wi.z);
                float wt = rough ? mis_weight(is.pdf, base_pdf) : 1.0f;
                f += beta * rho * (1.0f / PI_F) * fabs(is.wi.z) * wt * layer_transmittance(thickness, is.wi) * is_f;
                /* ... and a diffuse bounce, with light through the top along it */
                float4 v = next_uniform4(&rng);
                w = sample_cosine_hemisphere(v.x, v.y);
                beta *= rho;
                if (rough)
                    f += beta * layer_transmittance(thickness, w)
                         * exit_through_coating(top, w, wi, pdf_cosine_hemisphere(w.z));
            }
        }
    }
    return f / samples;
}

float pdf_coateddiffuse(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    Interface top = coating_of(m);
    int samples = (int)m->p2.w;
    float pdf;
    eval_interface(top, wo, wi, LOBE_REFLECTION, &pdf);
    float sum = samples * pdf;
    Rng rng = layer_rng(wi, wo, 2u);
    for (int k = 0; k < samples; ++k) {
        /* the density of the path top-transmission, base reflection, top-transmission */
        BSDFSample os, is;
        if (!enter_layer(top, wo, wi, &rng, &os, &is))
            continue;
        if (is_smooth(top)) {
            sum += pdf_cosine_hemisphere(-is.wi.z);
        } else {
            /* by MIS of the base's density towards -is.wi and the top's towards wi after a
               diffuse bounce */
            float4 v = next_uniform4(&rng);
            float3 r = sample_cosine_hemisphere(v.x, v.y);
            float r_pdf = pdf_cosine_hemisphere(-is.wi.z);
            sum += mis_weight(is.pdf, r_pdf) * r_pdf;
            float t_pdf;
            eval_interface(top, -r, wi, LOBE_REFLECTION | LOBE_TRANSMISSION, &t_pdf);
            sum += mis_weight(pdf_cosine_hemisphere(r.z), t_pdf) * t_pdf;
        }
    }
    return mix(1.0f / (4.0f * PI_F), sum / samples, 1.0f - LAYER_PDF_UNIFORM);
}

int sample_coateddiffuse(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    if (wo.z <= 0.0f)
        return 0;
    Interface top = coating_of(m);
    float3 rho = m->p0.xyz, albedo = m->p2.xyz;
    float thickness = m->p1.y, g = m->p1.z;
    int max_depth = (int)m->p1.w;
    if (!sample_interface(top, wo, u, LOBE_REFLECTION | LOBE_TRANSMISSION, s))
        return 0;
    if (s->lobe & LOBE_REFLECTION) {
        /* the coating's own reflection: the sample as it is (a delta where it is smooth) */
        if (!is_smooth(top))
            s->pdf = pdf_coateddiffuse(m, wo, s->wi);
        return 1;
    }
    Rng rng = layer_rng(wo, u, 3u);
    float3 beta = radiance_weight(s);
    float3 w = s->wi;
    float z = thickness;
    for (int depth = 0; depth < max_depth; ++depth) {
        float4 v = next_uniform4(&rng);
        if (!walk_survives(&beta, depth, v.w))
            return 0;
        if (any(albedo != 0.0f)) {
            float zp = z + copysign(-log1p(-v.x) * fabs(w.z), w.z);
            if (zp == z)
                return 0;
            if (0.0f < zp && zp < thickness) {
                float phase_pdf;
                float3 next = sample_hg(g, -w, (float2)(v.y, v.z), &phase_pdf);
                if (!(phase_pdf > 0.0f) || next.z == 0.0f)
                    return 0;
                beta *= albedo;
                w = next;
                z = zp;
                continue;
            }
            z = clamp(zp, 0.0f, thickness);
        } else {
            z = z == thickness ? 0.0f : thickness;
            beta *= layer_transmittance(thickness, w);
        }
        if (z == thickness) {
            BSDFSample bs;
            bs.eta = 1.0f;
            if (!sample_interface(top, -w, next_uniform4(&rng).xyz, LOBE_REFLECTION | LOBE_TRANSMISSION, &bs))
                return 0;
            beta *= radiance_weight(&bs);
            w = bs.wi;
            if (bs.lobe & LOBE_TRANSMISSION) {
                /* out of the layers: the walk's weight, and for MIS the estimated density */
                s->wi = w;
                s->weight = beta;
                s->eta = 1.0f;
                s->lobe = LOBE_GLOSSY | LOBE_REFLECTION;
                s->pdf = pdf_coateddiffuse(m, wo, w);
                return s->pdf > 0.0f;
            }
        } else {
            float4 c = next_uniform4(&rng);
            w = sample_cosine_hemisphere(c.x, c.y);
            beta *= rho;
        }
    }
    return 0;
}
