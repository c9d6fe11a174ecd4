/* The tent filter (Mitsuba 3's `tent`, pbrt-v4's `triangle`): weights max(0, 1 - |x| / radius)
 * times the same in y.
 *
 *   p->filter.x  radius, in pixels (Mitsuba's default 1, pbrt-v4's 2)
 *
 * Each axis by inverting the tent's distribution: its two halves are the triangle
 * distributions of u in [0, 1/2) and [1/2, 1). */

float sample_tent(float u, float radius)
{
    return radius * (u < 0.5f ? sqrt(2.0f * u) - 1.0f : 1.0f - sqrt(2.0f - 2.0f * u));
}

float2 sample_tent_filter(const RenderParams *p, float2 u, Rng *rng)
{
    return (float2)(sample_tent(u.x, p->filter.x), sample_tent(u.y, p->filter.x));
}

#ifdef BDPT
/* The density of sample_tent_filter's offsets along one axis at x: the tent over its area, the
 * radius (kernels/bdpt.cl splats light tracing with it). */
float pdf_tent_filter(const RenderParams *p, float x)
{
    float r = p->filter.x;
    return fmax(0.0f, 1.0f - fabs(x) / r) / r;
}
#endif
