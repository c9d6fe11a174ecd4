/* Robust ray spawning (Pharr, Jakob & Humphreys, "Physically Based Rendering", 4th ed., section
 * 6.8): each intersection point carries a conservative bound on its floating-point error, and a
 * ray leaving it starts just outside that box, on the side it leaves towards. It can then never
 * meet the surface it leaves, whatever the shape (concave meshes, overlapping shapes, refraction
 * later), with no scene-dependent epsilon. */

/* gamma(n) of pbrt section 6.8.1: a bound on the relative error of n float operations. */
#define MACHINE_EPSILON 0x1.0p-24f
float gamma_bound(int n)
{
    return (n * MACHINE_EPSILON) / (1.0f - n * MACHINE_EPSILON);
}

/* The origin for a ray leaving point p (error bound `error` per axis) in direction w, n the
 * geometric normal: p pushed along n by the error box's extent in that direction, then rounded
 * one float further away (pbrt-v4's OffsetRayOrigin). */
float3 offset_ray_origin(float3 p, float3 error, float3 n, float3 w)
{
    float d = dot(fabs(n), error);
    float3 offset = dot(w, n) < 0.0f ? -d * n : d * n;
    float3 po = p + offset;
    float3 up = nextafter(po, (float3)(INFINITY)), down = nextafter(po, (float3)(-INFINITY));
    return select(select(po, down, offset < 0.0f), up, offset > 0.0f);
}
