/* Robust ray spawning (Pharr, Jakob & Humphreys, "Physically Based Rendering", 4th ed., section
 * 6.8): each intersection point carries a conservative bound on its floating-point error, and a
 * ray leaving it starts just outside that box, on the side it leaves towards. It can then never
 * meet the surface it leaves, whatever the shape (concave meshes, overlapping shapes, refraction
 * later), with no scene-dependent epsilon. */

/* A ray towards a point stops this fraction of its length short of it (pbrt-v4's ShadowEpsilon,
 * in SpawnRayTo), so that it does not find the surface it is aimed at. */
#define SHADOW_EPSILON 1e-4f

/* gamma(n) of pbrt section 6.8.1: a bound on the relative error of n float operations. */
#define MACHINE_EPSILON 0x1.0p-24f
float gamma_bound(int n)
{
    return (n * MACHINE_EPSILON) / (1.0f - n * MACHINE_EPSILON);
}

/* x moved one float further in the direction of s's sign, per component (s != 0): pbrt-v4's
 * NextFloatUp and NextFloatDown, done on the bit pattern. A float's bits, read as an int, grow
 * with its magnitude whatever its sign, so a step away from zero adds one and a step towards
 * it subtracts one; from zero the step goes to the smallest normal float. Cheaper on GPUs than
 * OpenCL's nextafter, which also handles infinities and NaNs that cannot occur here. */
float3 step_float(float3 x, float3 s)
{
    int3 away = (x >= 0.0f) == (s > 0.0f);
    float3 y = as_float3(as_int3(x) + select((int3)(-1), (int3)(1), away));
    return select(y, copysign((float3)(FLT_MIN), s), x == 0.0f);
}

/* How far p must move along its unit geometric normal n to leave the box of its error bound
 * (`error` per axis): the box's extent in that direction. Surfaces keep this one number rather
 * than the bound (fewer live registers). */
float error_offset(float3 n, float3 error)
{
    return dot(fabs(n), error);
}

/* The origin for a ray leaving point p in direction w, n the geometric normal: p pushed along
 * n, to the side w leaves on, by d = error_offset(n, error), then rounded one float further
 * away (pbrt-v4's OffsetRayOrigin). */
float3 offset_ray_origin(float3 p, float d, float3 n, float3 w)
{
    float3 offset = dot(w, n) < 0.0f ? -d * n : d * n;
    float3 po = p + offset;
    return select(po, step_float(po, offset), offset != 0.0f);
}
