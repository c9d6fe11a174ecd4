/* Microfacet distributions: GGX and Beckmann with Smith shadowing, in the local shading frame
 * (z the macro-surface normal, x its tangent: kernels/frame.cl). The roughness alpha is a pair,
 * (alpha_x, alpha_y) along the tangent and the bitangent (Mitsuba 3's alpha_u and alpha_v;
 * equal for an isotropic surface): each distribution is its isotropic form of roughness 1
 * stretched by alpha (Heitz, "Understanding the Masking-Shadowing Function in
 * Microfacet-Based BRDFs", JCGT 3(2), 2014, section 5.3), which leaves the shadowing a
 * function of the projected roughness alpha(phi_v)^2 tan^2 theta_v =
 * (alpha_x^2 v_x^2 + alpha_y^2 v_y^2) / v_z^2.
 *
 * GGX (Trowbridge-Reitz): Walter et al., "Microfacet Models for Refraction through Rough
 * Surfaces", EGSR 2007; sampled by visible normals after Heitz, "Sampling the GGX Distribution of
 * Visible Normals", JCGT 7(4), 2018. Shadowing is Smith's separable form G1(wo) G1(wi), as
 * Mitsuba 3 uses. */

/* alpha(phi_v)^2 tan^2 theta_v of direction v (Heitz 2014, eq. 80) */
float projected_roughness2(float3 v, float2 alpha)
{
    float xy = alpha.x * alpha.x * v.x * v.x + alpha.y * alpha.y * v.y * v.y;
    return xy / (v.z * v.z);
}

/* D(m) = 1 / (pi a_x a_y (m_x^2 / a_x^2 + m_y^2 / a_y^2 + m_z^2)^2) */
float ggx_d(float3 m, float2 alpha)
{
    if (m.z <= 0.0f)
        return 0.0f;
    float t = m.x * m.x / (alpha.x * alpha.x) + m.y * m.y / (alpha.y * alpha.y) + m.z * m.z;
    return 1.0f / (PI_F * alpha.x * alpha.y * t * t);
}

/* Smith's G1(v, m) = 2 / (1 + sqrt(1 + alpha(phi)^2 tan^2 theta_v)); 0 when v sees m's back. */
float ggx_g1(float3 v, float3 m, float2 alpha)
{
    if (dot(v, m) * v.z <= 0.0f)
        return 0.0f;
    return 2.0f / (1.0f + sqrt(1.0f + projected_roughness2(v, alpha)));
}

/* The density of the normals sample_ggx_visible draws from wo (wo.z > 0):
 * D_wo(m) = G1(wo, m) max(0, wo.m) D(m) / wo.z (Heitz 2018, eq. 1). */
float pdf_ggx_visible(float3 wo, float3 m, float2 alpha)
{
    return ggx_g1(wo, m, alpha) * fmax(0.0f, dot(wo, m)) * ggx_d(m, alpha) / wo.z;
}

/* A microfacet normal seen from wo (wo.z > 0), from two uniforms (Heitz 2018, listing 1): wo is
 * stretched to the hemisphere configuration, a point is drawn on the projected disk of the
 * visible half-sphere, and the normal there is unstretched. */
float3 sample_ggx_visible(float3 wo, float2 alpha, float u1, float u2)
{
    float3 vh = unit((float3)(alpha.x * wo.x, alpha.y * wo.y, wo.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    float3 t1 = len2 > 0.0f ? (float3)(-vh.y, vh.x, 0.0f) * rsqrt(len2) : (float3)(1.0f, 0.0f, 0.0f);
    float3 t2 = cross(vh, t1);
    float r = sqrt(u1);
    float p1 = r * COS_TURNS(u2), p2 = r * SIN_TURNS(u2);
    float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * p2;
    float3 nh = p1 * t1 + p2 * t2 + sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
    return unit((float3)(alpha.x * nh.x, alpha.y * nh.y, fmax(1e-6f, nh.z)));
}

/* The Beckmann distribution (Walter et al. 2007, eq. 25), Mitsuba 3's default for its rough
 * materials: D(m) = exp(-(m_x^2 / a_x^2 + m_y^2 / a_y^2) / m_z^2) / (pi a_x a_y m_z^4). */
float beckmann_d(float3 m, float2 alpha)
{
    if (m.z <= 0.0f)
        return 0.0f;
    float cos2 = m.z * m.z;
    float e = (m.x * m.x / (alpha.x * alpha.x) + m.y * m.y / (alpha.y * alpha.y)) / cos2;
    return exp(-e) / (PI_F * alpha.x * alpha.y * cos2 * cos2);
}

/* Smith's G1 for Beckmann by Walter's rational approximation of 1 / (1 + Lambda) (Walter et al.
 * 2007, eq. 27; within 0.35 %), as Mitsuba 3 computes it: a = 1 / (alpha(phi) tan theta_v). */
float beckmann_g1(float3 v, float3 m, float2 alpha)
{
    if (dot(v, m) * v.z <= 0.0f)
        return 0.0f;
    float r2 = projected_roughness2(v, alpha);
    if (r2 <= 0.0f)
        return 1.0f;
    float a = rsqrt(r2);
    if (a >= 1.6f)
        return 1.0f;
    return (3.535f * a + 2.181f * a * a) / (1.0f + 2.276f * a + 2.577f * a * a);
}

/* erf^-1(x), x in (-1, 1): Giles, "Approximating the erfinv function", GPU Computing Gems
 * (2011), single precision, within a few float32 ulps. */
float erfinv_approx(float x)
{
    float w = -log((1.0f - x) * (1.0f + x)), p;
    if (w < 5.0f) {
        w -= 2.5f;
        p = 2.81022636e-08f;
        p = fma(p, w, 3.43273939e-07f); p = fma(p, w, -3.5233877e-06f);
        p = fma(p, w, -4.39150654e-06f); p = fma(p, w, 0.00021858087f);
        p = fma(p, w, -0.00125372503f); p = fma(p, w, -0.00417768164f);
        p = fma(p, w, 0.246640727f); p = fma(p, w, 1.50140941f);
    } else {
        w = sqrt(w) - 3.0f;
        p = -0.000200214257f;
        p = fma(p, w, 0.000100950558f); p = fma(p, w, 0.00134934322f);
        p = fma(p, w, -0.00367342844f); p = fma(p, w, 0.00573950773f);
        p = fma(p, w, -0.0076224613f); p = fma(p, w, 0.00943887047f);
        p = fma(p, w, 1.00167406f); p = fma(p, w, 2.83297682f);
    }
    return p * x;
}

/* A microfacet slope of the Beckmann distribution of alpha 1 seen from a direction at
 * cos theta (its visible slopes, x towards the direction): Jakob, "An Improved Visible Normal
 * Sampling Routine for the Beckmann Distribution" (2014). The slope's x has the CDF
 *     C(b) = (1 + b + tan theta exp(-erfinv(b)^2) / sqrt(pi)) / (1 + c + tan theta exp(-cot^2) / sqrt(pi)),
 * b = erf(x) in [-1, c = erf(cot theta)], inverted by Newton's method kept inside a bisection
 * interval; y is an independent normal slope. */
float2 sample_beckmann_slope(float cos_t, float u1, float u2)
{
    if (cos_t > 0.9999f) {                     /* normal incidence: the whole distribution */
        float r = sqrt(-log(1.0f - u1));
        return (float2)(r * COS_TURNS(u2), r * SIN_TURNS(u2));
    }
    float sin_t = sqrt(fmax(0.0f, 1.0f - cos_t * cos_t));
    float tan_t = sin_t / cos_t, cot_t = cos_t / sin_t;
    const float inv_sqrt_pi = 0.5641895835f;
    float a = -1.0f, c = erf(cot_t), x = fmax(u1, 1e-6f);
    float norm = 1.0f / (1.0f + c + inv_sqrt_pi * tan_t * exp(-cot_t * cot_t));
    /* a close first guess (Jakob 2014, a fit in theta) */
    float theta = acos(cos_t);
    float b = c - (1.0f + c) * pow(1.0f - x, 1.0f + theta * (-0.876f + theta * (0.4265f - 0.0594f * theta)));
    for (int it = 0; it < 10; ++it) {
        if (!(b >= a && b <= c))               /* outside the interval (or NaN): bisect */
            b = 0.5f * (a + c);
        float e = erfinv_approx(b);
        float value = norm * (1.0f + b + inv_sqrt_pi * tan_t * exp(-e * e)) - x;
        if (fabs(value) < 1e-5f)
            break;
        if (value > 0.0f)
            c = b;
        else
            a = b;
        b -= value / (norm * (1.0f - e * tan_t));
    }
    return (float2)(erfinv_approx(b), erfinv_approx(2.0f * fmax(u2, 1e-6f) - 1.0f));
}

/* A microfacet normal of the Beckmann distribution seen from wo (wo.z > 0), of density
 * G1(wo, m) max(0, wo.m) D(m) / wo.z: wo stretched to roughness 1, a visible slope drawn there,
 * turned to wo's azimuth, unstretched (Heitz and d'Eon 2014, section 4). The G1 of that density
 * is Smith's exact one; pdf_beckmann_visible and the BSDFs use Walter's approximation
 * (beckmann_g1), as Mitsuba 3 does, which follows it to 0.35 %: the weights' expectation is off
 * by that much at most, at grazing angles. */
float3 sample_beckmann_visible(float3 wo, float2 alpha, float u1, float u2)
{
    float3 w = unit((float3)(alpha.x * wo.x, alpha.y * wo.y, wo.z));
    float xy = sqrt(w.x * w.x + w.y * w.y);
    float cos_phi = xy > 0.0f ? w.x / xy : 1.0f, sin_phi = xy > 0.0f ? w.y / xy : 0.0f;
    float2 s = sample_beckmann_slope(w.z, u1, u2);
    float2 r = (float2)(cos_phi * s.x - sin_phi * s.y, sin_phi * s.x + cos_phi * s.y) * alpha;
    return unit((float3)(-r.x, -r.y, 1.0f));
}

/* The density of the normals sample_beckmann_visible draws from wo (wo.z > 0). */
float pdf_beckmann_visible(float3 wo, float3 m, float2 alpha)
{
    return beckmann_g1(wo, m, alpha) * fmax(0.0f, dot(wo, m)) * beckmann_d(m, alpha) / wo.z;
}
