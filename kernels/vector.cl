/* Length and direction of a vector, by sqrt and rsqrt of dot(v, v). OpenCL's length and
 * normalize rescale v first, to guard dot(v, v) against overflow and underflow; that costs
 * registers and time in every bounce (docs/notes/performance-2026-11.md, 2026-11-22: vectors without
 * OpenCL's guard). The vectors given here cannot need the guard: directions, and
 * distances within a scene, which would have to exceed sqrt(FLT_MAX) = 1.8e19, where the sphere
 * test's own dot(f, f) fails first. Triangles' edge products, which can be tiny, keep OpenCL's. */

float norm(float3 v)
{
    return sqrt(dot(v, v));
}

float3 unit(float3 v)
{
    return v * rsqrt(dot(v, v));
}
