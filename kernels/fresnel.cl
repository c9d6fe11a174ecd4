/* The Fresnel equations for unpolarised light (Born & Wolf, "Principles of Optics", section
 * 1.5; pbrt-v4 section 9.3). */

/* Reflectance of a smooth interface between dielectrics. eta = n_inside / n_outside, the inside
 * being the side opposite the normal; cos_i = cos of the incident direction with the normal,
 * negative when it arrives from inside. Returns R (1 under total internal reflection) and, in
 * *cos_t, the transmitted direction's cosine (on the other side, so of opposite sign) and in
 * *eta_ti = n_i / n_t, the factor Snell's law scales the tangential part by. */
float fresnel_dielectric(float cos_i, float eta, float *cos_t, float *eta_ti)
{
    float e = cos_i >= 0.0f ? eta : 1.0f / eta;          /* n_t / n_i */
    *eta_ti = 1.0f / e;
    float ci = fabs(cos_i);
    float sin2_t = (1.0f - ci * ci) / (e * e);            /* Snell's law */
    if (sin2_t >= 1.0f) {
        *cos_t = 0.0f;
        return 1.0f;
    }
    float ct = sqrt(1.0f - sin2_t);
    *cos_t = cos_i >= 0.0f ? -ct : ct;
    float r_s = (ci - e * ct) / (ci + e * ct);
    float r_p = (e * ci - ct) / (e * ci + ct);
    return 0.5f * (r_s * r_s + r_p * r_p);
}

/* Reflectance of a conductor of complex IOR eta + i k (relative to the outside) at incidence
 * cos_i >= 0, per channel: the exact unpolarised form (pbrt-v3 section 8.2.1, after Shirley's
 * derivation of the s and p terms through a^2 + b^2). */
float3 fresnel_conductor(float cos_i, float3 eta, float3 k)
{
    float cos2 = cos_i * cos_i, sin2 = 1.0f - cos2;
    float3 eta2 = eta * eta, k2 = k * k;
    float3 t0 = eta2 - k2 - sin2;
    float3 a2b2 = sqrt(fmax(t0 * t0 + 4.0f * eta2 * k2, 0.0f));
    float3 a = sqrt(fmax(0.5f * (a2b2 + t0), 0.0f));
    float3 t1 = a2b2 + cos2, t2 = 2.0f * cos_i * a;
    float3 r_s = (t1 - t2) / (t1 + t2);
    float3 t3 = cos2 * a2b2 + sin2 * sin2, t4 = t2 * sin2;
    float3 r_p = r_s * (t3 - t4) / (t3 + t4);
    return 0.5f * (r_s + r_p);
}
