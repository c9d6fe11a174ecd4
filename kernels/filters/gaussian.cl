/* The gaussian filter (Mitsuba 3's `gaussian`, pbrt-v4's `gaussian`): weights
 * max(0, g(x) - g(radius)) times the same in y, g(x) = exp(-x^2 / (2 stddev^2)): a gaussian
 * shifted down to reach 0 at its radius.
 *
 *   p->filter.x  radius, in pixels (Mitsuba's default 4 stddev = 2, pbrt-v4's 1.5)
 *   p->filter.y  stddev, in pixels (0.5 in both)
 *   p->filter.z  g(radius)
 *
 * Each axis by rejection, which samples the weights exactly, so that every sample keeps weight
 * 1: candidates from the gaussian itself (Box-Muller), kept with probability
 * (g(x) - g(radius)) / g(x); or, for a radius under two stddev, where too many of those would be
 * refused, uniform candidates kept with probability (g(x) - g(radius)) / (1 - g(radius)).
 * Either keeps more than half its candidates; after GAUSSIAN_TRIES refusals (a chance below
 * 2^-64) the centre is taken. */

#define GAUSSIAN_TRIES 64

float sample_gaussian(const RenderParams *p, float u0, float u1, Rng *rng)
{
    float radius = p->filter.x, stddev = p->filter.y, bias = p->filter.z;
    for (int i = 0; i < GAUSSIAN_TRIES; ++i) {
        float x, proposal;
        if (radius >= 2.0f * stddev) {
            x = stddev * sqrt(-2.0f * log(1.0f - u0)) * COS_TURNS(u1);
            proposal = exp(-x * x / (2.0f * stddev * stddev));
        } else {
            x = radius * (2.0f * u0 - 1.0f);
            proposal = 1.0f - bias;
        }
        float4 v = next_uniform4(rng);
        if (fabs(x) <= radius && v.x * proposal < exp(-x * x / (2.0f * stddev * stddev)) - bias)
            return x;
        u0 = v.y;
        u1 = v.z;
    }
    return 0.0f;
}

float2 sample_gaussian_filter(const RenderParams *p, float2 u, Rng *rng)
{
    float4 v = next_uniform4(rng);
    return (float2)(sample_gaussian(p, u.x, u.y, rng), sample_gaussian(p, v.x, v.y, rng));
}

#ifdef BDPT
/* The density of sample_gaussian_filter's offsets along one axis at x: g(x) - g(radius) over its
 * integral from -radius to radius, stddev sqrt(2 pi) erf(radius / (stddev sqrt 2)) - 2 radius
 * g(radius) (kernels/bdpt.cl splats light tracing with it). */
float pdf_gaussian_filter(const RenderParams *p, float x)
{
    float radius = p->filter.x, stddev = p->filter.y, bias = p->filter.z;
    if (fabs(x) > radius)
        return 0.0f;
    float area = stddev * sqrt(2.0f * PI_F) * erf(radius / (stddev * sqrt(2.0f))) - 2.0f * radius * bias;
    return fmax(0.0f, exp(-x * x / (2.0f * stddev * stddev)) - bias) / area;
}
#endif
