/* The sphere range: round spheres kept by world centre and radius (types.h: Sphere), the first
 * primitives of a scene; intersection, the surface at a hit, and sampling the cone of directions
 * it subtends (for next-event estimation). They are solid: their outward normal is the front.
 * The analytic sphere kind (kernels/shapes/sphere.cl: any transform, partial spheres) meets its
 * sphere through sphere_crossings. */

/* Both t where the line o + t d meets the sphere, nearer first, or INFINITY twice; d must be
 * unit length. The discriminant is computed as r^2 - |f - (f.d) d|^2 rather than b^2 - c, and
 * the two roots as c / q and q, following Haines et al., "Precision Improvements for Ray/Sphere Intersection",
 * Ray Tracing Gems, ch. 7 (2019): both stay accurate for the r = 1000 ground seen from afar. */
float2 sphere_crossings(Sphere s, float3 o, float3 d)
{
    float3 f = o - s.xyz;
    float b = dot(f, d);
    float3 l = f - b * d;
    float disc = s.w * s.w - dot(l, l);
    if (disc < 0.0f)
        return (float2)(INFINITY);
    float c = dot(f, f) - s.w * s.w;
    float q = -(b + copysign(sqrt(disc), b));
    float t0 = c / q, t1 = q;
    return (float2)(fmin(t0, t1), fmax(t0, t1));
}

/* Nearest t in (0, t_max) where o + t d meets the sphere, or INFINITY; d unit length. */
float intersect_range_sphere(Sphere s, float3 o, float3 d, float t_max)
{
    float2 t = sphere_crossings(s, o, d);
    /* A ray starting inside the sphere meets it only on the way out. */
    float t_hit = t.x > 0.0f ? t.x : t.y;
    return (t_hit > 0.0f && t_hit < t_max) ? t_hit : INFINITY;
}

/* The hit point of o + t d, projected back onto the sphere, with its error bound and outward
 * unit normal. pbrt-v4 (section 6.8.5) bounds the reprojected point relative to the centre by
 * gamma(5) |p| for a correctly rounded sqrt and division; here the scale is r rsqrt(|p|^2):
 * gamma(3) in the dot product, halved by the square root, OpenCL's 2 ulp (4 epsilon) for rsqrt
 * and two products make 7.5 epsilon, so gamma(8); plus the rounding of adding the centre back. */
void sphere_surface(Sphere s, float3 o, float3 d, float t, float3 *p, float3 *error, float3 *n)
{
    float3 rel = o + t * d - s.xyz;
    rel *= s.w * rsqrt(dot(rel, rel));
    *n = rel / s.w;
    *p = s.xyz + rel;
    *error = gamma_bound(8) * fabs(rel) + gamma_bound(2) * fabs(*p);
}

/* Texture coordinates of point p on the sphere, as Mitsuba 3's `sphere` gives them:
 * u = phi / 2 pi, phi = atan2(y, x) in [0, 2 pi), and v = theta / pi, theta the angle from +z,
 * in the sphere's frame (a sphere keeps no rotation: the world's axes). */
float2 range_sphere_uv(Sphere s, float3 p)
{
    float3 n = (p - s.xyz) / s.w;
    float phi = atan2(n.y, n.x);
    phi = phi < 0.0f ? phi + 2.0f * PI_F : phi;
    return (float2)(phi / (2.0f * PI_F), acos(clamp(n.z, -1.0f, 1.0f)) / PI_F);
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
    float3 v = (float3)(COS_TURNS(u2) * sin_t, SIN_TURNS(u2) * sin_t, cos_t);
    return to_world(v, unit(s.xyz - p));
}
