/* The GGX (Trowbridge-Reitz) microfacet distribution with Smith shadowing, isotropic roughness
 * alpha, in the local frame (z the macro-surface normal): Walter et al., "Microfacet Models for
 * Refraction through Rough Surfaces", EGSR 2007; sampled by visible normals after Heitz,
 * "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), 2018. Shadowing is Smith's
 * separable form G1(wo) G1(wi), as Mitsuba 3 uses. */

/* D(m) = 1 / (pi a^2 ((m_x^2 + m_y^2) / a^2 + m_z^2)^2) */
float ggx_d(float3 m, float alpha)
{
    if (m.z <= 0.0f)
        return 0.0f;
    float a2 = alpha * alpha;
    float t = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
    return 1.0f / (PI_F * a2 * t * t);
}

/* Smith's G1(v, m) = 2 / (1 + sqrt(1 + a^2 tan^2 theta_v)); 0 when v sees m's back. */
float ggx_g1(float3 v, float3 m, float alpha)
{
    if (dot(v, m) * v.z <= 0.0f)
        return 0.0f;
    float cos2 = v.z * v.z;
    float tan2 = fmax(0.0f, 1.0f - cos2) / cos2;
    return 2.0f / (1.0f + sqrt(1.0f + alpha * alpha * tan2));
}

/* The density of the normals sample_ggx_visible draws from wo (wo.z > 0):
 * D_wo(m) = G1(wo, m) max(0, wo.m) D(m) / wo.z (Heitz 2018, eq. 1). */
float pdf_ggx_visible(float3 wo, float3 m, float alpha)
{
    return ggx_g1(wo, m, alpha) * fmax(0.0f, dot(wo, m)) * ggx_d(m, alpha) / wo.z;
}

/* A microfacet normal seen from wo (wo.z > 0), from two uniforms (Heitz 2018, listing 1): wo is
 * stretched to the hemisphere configuration, a point is drawn on the projected disk of the
 * visible half-sphere, and the normal there is unstretched. */
float3 sample_ggx_visible(float3 wo, float alpha, float u1, float u2)
{
    float3 vh = unit((float3)(alpha * wo.x, alpha * wo.y, wo.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    float3 t1 = len2 > 0.0f ? (float3)(-vh.y, vh.x, 0.0f) * rsqrt(len2) : (float3)(1.0f, 0.0f, 0.0f);
    float3 t2 = cross(vh, t1);
    float r = sqrt(u1), phi = 2.0f * PI_F * u2;
    float p1 = r * cos(phi), p2 = r * sin(phi);
    float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * p2;
    float3 nh = p1 * t1 + p2 * t2 + sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
    return unit((float3)(alpha * nh.x, alpha * nh.y, fmax(1e-6f, nh.z)));
}
