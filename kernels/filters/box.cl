/* The box filter (Mitsuba 3's and pbrt-v4's `box`): equal weights within `radius` of the
 * pixel's centre along each axis (0.5: the pixel itself).
 *
 *   p->filter.x  radius, in pixels */

float2 sample_box_filter(const RenderParams *p, float2 u, Rng *rng)
{
    return (2.0f * u - 1.0f) * p->filter.x;
}

#ifdef BDPT
/* The density of sample_box_filter's offsets along one axis at x (kernels/bdpt.cl splats light
 * tracing with it). */
float pdf_box_filter(const RenderParams *p, float x)
{
    return fabs(x) <= p->filter.x ? 0.5f / p->filter.x : 0.0f;
}
#endif
