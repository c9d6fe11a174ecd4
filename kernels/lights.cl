/* Light sampling for next-event estimation: choosing an emissive sphere, sampling the cone of
 * directions it subtends, and the densities multiple importance sampling needs. */

/* Power heuristic with beta = 2 (Veach, "Robust Monte Carlo Methods for Light Transport
 * Simulation", 1997, section 9.2.4): the weight of the technique with density a. */
float mis_weight(float a, float b)
{
    return a * a / (a * a + b * b);
}

/* Walker's alias method: one uniform number picks a light in proportion to its power. */
int pick_light(const global Light *lights, int count, float u)
{
    float x = u * count;
    int i = min((int)x, count - 1);
    return (x - i) < lights[i].keep ? i : lights[i].alias;
}

/* 1 - cos(theta_max) of the cone a sphere subtends from p, as sin^2 / (1 + cos) to keep
 * precision for small, far spheres; 0 when p is inside the sphere. */
float cone_solid_angle_factor(Sphere s, float3 p)
{
    float3 c = s.xyz - p;
    float sin2 = s.w * s.w / dot(c, c);
    if (sin2 >= 1.0f)
        return 0.0f;
    return sin2 / (1.0f + sqrt(1.0f - sin2));
}

/* Density (per solid angle) of sample_sphere_cone's directions: uniform over the cone. */
float pdf_sphere_cone(Sphere s, float3 p)
{
    float k = cone_solid_angle_factor(s, p);
    return k > 0.0f ? 1.0f / (2.0f * PI_F * k) : 0.0f;
}

/* A direction from p, uniform in the cone subtended by the sphere (pbrt-v4, section 6.2.4):
 * cos(theta) = 1 - u1 (1 - cos(theta_max)). */
float3 sample_sphere_cone(Sphere s, float3 p, float u1, float u2)
{
    float k = cone_solid_angle_factor(s, p);
    float one_minus_cos = u1 * k;
    float cos_t = 1.0f - one_minus_cos;
    float sin_t = sqrt(max(0.0f, one_minus_cos * (2.0f - one_minus_cos)));
    float3 v = (float3)(cos(2.0f * PI_F * u2) * sin_t, sin(2.0f * PI_F * u2) * sin_t, cos_t);
    return to_world(v, normalize(s.xyz - p));
}
