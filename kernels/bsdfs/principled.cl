/* principled: Disney's principled BSDF as Mitsuba 3 implements it (its `principled`, what
 * Blender's Principled BSDF exports to): Burley, "Physically Based Shading at Disney",
 * SIGGRAPH 2012 course notes, and "Extending the Disney BRDF to a BSDF with Integrated
 * Subsurface Scattering", 2015. A sum of lobes, with brdf = (1 - metallic)(1 - spec_trans) and
 * bsdf = (1 - metallic) spec_trans:
 *   diffuse       brdf base_color / pi ((1 - F_o / 2)(1 - F_i / 2) + retro-reflection), lerped
 *                 by flatness towards Hanrahan-Krueger's fake subsurface; F_x = (1 - cos)^5
 *   sheen         sheen (1 - metallic) (1 - cos_d)^5 lerp(1, tint, sheen_tint), tint = the
 *                 base colour over its luminance (no 1 / pi, as Disney's)
 *   specular      anisotropic GGX reflection, F D G / (4 cos_o cos_i), whose F blends the
 *                 dielectric's exact reflectance, the metal's Schlick of base_color and the
 *                 tinted dielectric's Schlick (principled_fresnel)
 *   transmission  bsdf sqrt(base_color) times Walter et al.'s refraction through the same GGX
 *                 microfacets, with radiance's (n_o / n_i)^2 compression
 *   clearcoat     0.25 clearcoat F_schlick(0.04) D_GTR1 G, G Smith's GGX of alpha 0.25, without
 *                 1 / (4 cos cos) (Disney's form, which Mitsuba keeps)
 * From inside (wo.z < 0, where spec_trans is not 0) the surface is the rough dielectric
 * interface alone, its reflection weighted by bsdf. Directions the microfacets cannot connect
 * (wo and wi not on the sides of h they lie on) get no specular, transmission or clearcoat.
 *
 * The parameters are read through PRINCIPLED_<PARAM> (eta, n inside / n outside, at least 1),
 * generated from their slots on the host (app/materials/principled.py).
 *
 * Sampling picks a lobe with probabilities proportional to (outside) specular rate (1 - bsdf
 * (1 - F)), specular rate bsdf (1 - F), 0.25 clearcoat clearcoat rate and brdf diffuse rate,
 * (inside) F and 1 - F, F the dielectric reflectance at a normal drawn from GGX's visible
 * normals, as Mitsuba 3 does; the specular lobes' sum does not depend on F, so the choice is
 * consistent with pdf_principled at the direction it yields. The clearcoat draws GTR1's normals
 * (not visible ones), the diffuse lobe the cosine. */

/* GGX's (alpha_x, alpha_y) from roughness and anisotropic (Burley 2012, addendum B.2: aspect
 * sqrt(1 - 0.9 anisotropic)), at least 0.001, as Mitsuba's calc_dist_params. */
float2 principled_alpha(MaterialRef m)
{
    float r2 = PRINCIPLED_ROUGHNESS(m) * PRINCIPLED_ROUGHNESS(m), aspect = sqrt(1.0f - 0.9f * PRINCIPLED_ANISOTROPIC(m));
    return fmax((float2)(r2 / aspect, r2 * aspect), 0.001f);
}

/* The clearcoat's GTR1 roughness: 0.1 at gloss 0 to 0.001 at gloss 1 (Burley 2012, B.2). */
float clearcoat_alpha(MaterialRef m)
{
    return mix(0.1f, 0.001f, PRINCIPLED_CLEARCOAT_GLOSS(m));
}

/* Schlick's Fresnel weight (1 - cos)^5 */
float schlick_weight(float cos_t)
{
    float x = clamp(1.0f - cos_t, 0.0f, 1.0f), x2 = x * x;
    return x2 * x2 * x;
}

/* Schlick's approximation from r0 at a microfacet seen at cos_h from outside; with eta at
 * least 1 this is what Mitsuba's calc_schlick gives there. */
float3 schlick(float3 r0, float cos_h)
{
    return r0 + (1.0f - r0) * schlick_weight(cos_h);
}

/* The base colour over its luminance (white where it is black): the hue that spec_tint and
 * sheen_tint lean towards. */
float3 principled_tint(float3 base)
{
    float lum = luminance(base);
    return lum > 0.0f ? base / lum : (float3)(1.0f);
}

/* GTR1 (Burley 2012, B.2): D(h) = (a^2 - 1) / (pi log(a^2) (1 + (a^2 - 1) cos^2 theta_h)). */
float gtr1_d(float3 h, float a)
{
    float a2 = a * a;
    float d = (a2 - 1.0f) / (PI_F * log(a2) * (1.0f + (a2 - 1.0f) * h.z * h.z));
    return d * h.z > 1e-20f ? d : 0.0f;
}

/* A GTR1 normal, of density D(h) cos theta_h: cos^2 theta = (1 - a^(2(1 - u2))) / (1 - a^2). */
float3 sample_gtr1(float a, float u1, float u2)
{
    float a2 = a * a;
    float cos2 = (1.0f - pow(a2, 1.0f - u2)) / (1.0f - a2);
    float sin_t = sqrt(fmax(0.0f, 1.0f - cos2)), cos_t = sqrt(fmax(0.0f, cos2));
    return (float3)(COS_TURNS(u1) * sin_t, SIN_TURNS(u1) * sin_t, cos_t);
}

/* The specular reflection's Fresnel term seen from outside at cos_h, from the dielectric's
 * exact reflectance f_dielectric (Mitsuba's principled_fresnel). */
float3 principled_fresnel(MaterialRef m, float f_dielectric, float cos_h)
{
    float metallic = PRINCIPLED_METALLIC(m), tint = PRINCIPLED_SPEC_TINT(m), eta = PRINCIPLED_ETA(m);
    float r0 = (eta - 1.0f) / (eta + 1.0f);
    float3 tinted = schlick(principled_tint(PRINCIPLED_BASE_COLOR(m)) * (r0 * r0), cos_h);
    return (1.0f - metallic) * (1.0f - tint) * f_dielectric + metallic * schlick(PRINCIPLED_BASE_COLOR(m), cos_h)
           + (1.0f - metallic) * tint * tinted;
}

/* The lobes' choice probabilities at a microfacet of dielectric reflectance fr, seen from
 * outside or not: specular reflection, transmission, clearcoat and diffuse, summing to 1. */
float4 principled_lobes(MaterialRef m, int outside, float fr)
{
    float metallic = PRINCIPLED_METALLIC(m), spec_trans = PRINCIPLED_SPEC_TRANS(m);
    float bsdf = (1.0f - metallic) * spec_trans;
    float specular = PRINCIPLED_MAIN_SPECULAR_SAMPLING_RATE(m);
    float4 p = outside ? (float4)(specular * (1.0f - bsdf * (1.0f - fr)), specular * bsdf * (1.0f - fr),
                                  0.25f * PRINCIPLED_CLEARCOAT(m) * PRINCIPLED_CLEARCOAT_SAMPLING_RATE(m),
                                  (1.0f - metallic) * (1.0f - spec_trans) * PRINCIPLED_DIFFUSE_REFLECTANCE_SAMPLING_RATE(m))
                       : (float4)(fr, 1.0f - fr, 0.0f, 0.0f);
    return p / (p.x + p.y + p.z + p.w);
}

/* The microfacet normal of a pair of directions: their (generalised) half vector turned
 * outside, with e = n(wi's side) / n(wo's side) (1 for a reflection). */
float3 principled_half_vector(float3 wo, float3 wi, float e)
{
    float3 h = unit(wo + e * wi);
    return h.z < 0.0f ? -h : h;
}

float3 eval_principled(MaterialRef m, float3 wo, float3 wi)
{
    if (wo.z == 0.0f || wi.z == 0.0f)
        return (float3)(0.0f);
    float3 base = PRINCIPLED_BASE_COLOR(m);
    float metallic = PRINCIPLED_METALLIC(m), spec_trans = PRINCIPLED_SPEC_TRANS(m), eta = PRINCIPLED_ETA(m);
    float brdf = (1.0f - metallic) * (1.0f - spec_trans), bsdf = (1.0f - metallic) * spec_trans;
    int outside = wo.z > 0.0f, reflect = wo.z * wi.z > 0.0f;
    float e = reflect ? 1.0f : (outside ? eta : 1.0f / eta);
    float3 h = principled_half_vector(wo, wi, e);
    float wo_h = dot(wo, h), wi_h = dot(wi, h);
    float3 f = (float3)(0.0f);
    if (wo_h * wo.z > 0.0f && wi_h * wi.z > 0.0f) {
        float2 alpha = principled_alpha(m);
        float cos_t, eta_ti;
        float fr = fresnel_dielectric(wo_h, eta, &cos_t, &eta_ti);
        float dg = ggx_d(h, alpha) * ggx_g1(wo, h, alpha) * ggx_g1(wi, h, alpha);
        if (reflect && fr > 0.0f) {
            float3 F = outside ? principled_fresnel(m, fr, wo_h) : (float3)(bsdf * fr);
            f += F * (dg / (4.0f * fabs(wo.z * wi.z)));
        } else if (!reflect && bsdf > 0.0f) {
            /* Walter et al. 2007, eq. 21, times (n_o / n_i)^2 = 1 / e^2 */
            float denom = wo_h + e * wi_h;
            f += sqrt(base) * (bsdf * (1.0f - fr) * dg * fabs(wo_h * wi_h) / (denom * denom * fabs(wo.z * wi.z)));
        }
        if (reflect && outside && PRINCIPLED_CLEARCOAT(m) > 0.0f) {
            float a = 0.25f;
            float g = ggx_g1(wo, h, (float2)(a)) * ggx_g1(wi, h, (float2)(a));
            float fc = 0.04f + 0.96f * schlick_weight(wo_h);
            f += (float3)(0.25f * PRINCIPLED_CLEARCOAT(m) * fc * gtr1_d(h, clearcoat_alpha(m)) * g);
        }
    }
    if (reflect && outside && brdf > 0.0f) {
        float fo = schlick_weight(wi.z), fi = schlick_weight(wo.z);
        float cos_d = dot(h, wi);
        float rr = 2.0f * PRINCIPLED_ROUGHNESS(m) * cos_d * cos_d;                /* retro-reflection */
        float diffuse = (1.0f - 0.5f * fi) * (1.0f - 0.5f * fo) + rr * (fo + fi + fo * fi * (rr - 1.0f));
        /* Hanrahan-Krueger's fake subsurface (Burley 2012, B.1) */
        float fss = mix(1.0f, 0.5f * rr, fo) * mix(1.0f, 0.5f * rr, fi);
        float subsurface = 1.25f * (fss * (1.0f / (wi.z + wo.z) - 0.5f) + 0.5f);
        f += base * (brdf / PI_F * mix(diffuse, subsurface, PRINCIPLED_FLATNESS(m)));
        if (PRINCIPLED_SHEEN(m) > 0.0f)
            f += mix((float3)(1.0f), principled_tint(base), PRINCIPLED_SHEEN_TINT(m)) * (PRINCIPLED_SHEEN(m) * (1.0f - metallic) * schlick_weight(fabs(cos_d)));
    }
    return f;
}

float pdf_principled(MaterialRef m, float3 wo, float3 wi)
{
    int outside = wo.z > 0.0f, reflect = wo.z * wi.z > 0.0f;
    float eta = PRINCIPLED_ETA(m);
    if (wo.z == 0.0f || wi.z == 0.0f || (!outside && PRINCIPLED_SPEC_TRANS(m) * (1.0f - PRINCIPLED_METALLIC(m)) <= 0.0f))
        return 0.0f;
    float e = reflect ? 1.0f : (outside ? eta : 1.0f / eta);
    float3 h = principled_half_vector(wo, wi, e);
    float wo_h = dot(wo, h), wi_h = dot(wi, h);
    float cos_t, eta_ti;
    float4 p = principled_lobes(m, outside, fresnel_dielectric(wo_h, eta, &cos_t, &eta_ti));
    float pdf = reflect ? p.w * pdf_cosine_hemisphere(wi.z) : 0.0f;
    if (wo_h * wo.z <= 0.0f || wi_h * wi.z <= 0.0f)
        return pdf;
    /* dh / dwi: reflection's 1 / (4 wi.h) or refraction's e^2 wi.h / (wo.h + e wi.h)^2 (Walter
     * et al. 2007, eqs. 14 and 17) */
    float denom = wo_h + e * wi_h;
    float jacobian = reflect ? 1.0f / (4.0f * fabs(wi_h)) : e * e * fabs(wi_h) / (denom * denom);
    float pdf_h = pdf_ggx_visible(outside ? wo : -wo, h, principled_alpha(m));
    pdf += (reflect ? p.x : p.y) * pdf_h * jacobian;
    if (reflect)
        pdf += p.z * gtr1_d(h, clearcoat_alpha(m)) * h.z * jacobian;
    return pdf;
}

int sample_principled(MaterialRef m, float3 wo, float3 u, BSDFSample *s)
{
    int outside = wo.z > 0.0f;
    if (wo.z == 0.0f || (!outside && PRINCIPLED_SPEC_TRANS(m) * (1.0f - PRINCIPLED_METALLIC(m)) <= 0.0f))
        return 0;
    float3 up = outside ? wo : -wo;
    float3 h = sample_ggx_visible(up, principled_alpha(m), u.y, u.z);
    float wo_h = dot(wo, h);
    float cos_t, eta_ti;
    float4 p = principled_lobes(m, outside, fresnel_dielectric(wo_h, PRINCIPLED_ETA(m), &cos_t, &eta_ti));
    s->eta = 1.0f;
    if (u.x < p.w) {
        s->wi = sample_cosine_hemisphere(u.y, u.z);
        s->lobe = LOBE_DIFFUSE | LOBE_REFLECTION;
    } else if (u.x < p.w + p.z) {
        float3 hc = sample_gtr1(clearcoat_alpha(m), u.y, u.z);
        s->wi = 2.0f * dot(wo, hc) * hc - wo;
        s->lobe = LOBE_GLOSSY | LOBE_REFLECTION;
    } else if (u.x < p.w + p.z + p.y) {
        /* Snell's law about h: the tangential part turned round and scaled by n_i / n_t */
        s->wi = (eta_ti * wo_h + cos_t) * h - eta_ti * wo;
        s->eta = 1.0f / eta_ti;
        s->lobe = LOBE_GLOSSY | LOBE_TRANSMISSION;
    } else {
        s->wi = 2.0f * wo_h * h - wo;
        s->lobe = LOBE_GLOSSY | LOBE_REFLECTION;
    }
    if ((s->lobe & LOBE_REFLECTION) ? s->wi.z * wo.z <= 0.0f : s->wi.z * wo.z >= 0.0f)
        return 0;
    s->pdf = pdf_principled(m, wo, s->wi);
    if (!(s->pdf > 0.0f))
        return 0;
    s->weight = eval_principled(m, wo, s->wi) * (fabs(s->wi.z) / s->pdf);
    return 1;
}
