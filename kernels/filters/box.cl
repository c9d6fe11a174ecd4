/* The box filter (Mitsuba 3's and pbrt-v4's `box`): equal weights within `radius` of the
 * pixel's centre along each axis (0.5: the pixel itself).
 *
 *   p->filter.x  radius, in pixels */

float2 sample_box_filter(const RenderParams *p, float2 u, Rng *rng)
{
    return (2.0f * u - 1.0f) * p->filter.x;
}
