/* Warps from the unit square to directions, in a local frame whose z axis is the lobe's axis. */

#define PI_F 3.14159265358979323846f

/* cos(2 pi t) and sin(2 pi t) of t turns: every sampler's azimuth. On a CPU (PoCL) cos and sin
 * reduce their argument modulo pi / 2 the slow way; cospi and sinpi reduce a multiple of pi
 * exactly and cheaply, and 2 t needs no rounded product with pi, so CPUs take them. GPUs gained
 * nothing from them, and compile the code they had (docs/notes/performance-2026-11.md, 2026-11-25:
 * azimuths in turns). */
#ifdef CPU_DEVICE
#define COS_TURNS(t) cospi(2.0f * (t))
#define SIN_TURNS(t) sinpi(2.0f * (t))
#else
#define COS_TURNS(t) cos(2.0f * PI_F * (t))
#define SIN_TURNS(t) sin(2.0f * PI_F * (t))
#endif

/* An orthonormal basis around a unit vector n (Duff et al., "Building an Orthonormal Basis,
 * Revisited", JCGT 6(1), 2017): branch-free and exact for every n. */
void make_frame(float3 n, float3 *t, float3 *b)
{
    float sign = copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = (float3)(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = (float3)(c, sign + n.y * n.y * a, -n.y);
}

/* v from the frame of make_frame(axis) to world space, and back. The integrator rebuilds the
 * shading frame on each use rather than keeping it: nine floats fewer live in registers. */
float3 to_world(float3 v, float3 axis)
{
    float3 t, b;
    make_frame(axis, &t, &b);
    return v.x * t + v.y * b + v.z * axis;
}

float3 to_frame(float3 v, float3 axis)
{
    float3 t, b;
    make_frame(axis, &t, &b);
    return (float3)(dot(v, t), dot(v, b), dot(v, axis));
}

/* Cosine-weighted hemisphere, the report's eq. (3); pdf cos(theta) / pi. */
float3 sample_cosine_hemisphere(float r1, float r2)
{
    float s = sqrt(1.0f - r2);
    return (float3)(COS_TURNS(r1) * s, SIN_TURNS(r1) * s, sqrt(r2));
}

float pdf_cosine_hemisphere(float cos_theta)
{
    return cos_theta > 0.0f ? cos_theta / PI_F : 0.0f;
}

/* The whole sphere, uniformly; pdf 1 / (4 pi). */
float3 sample_uniform_sphere(float r1, float r2)
{
    float z = 1.0f - 2.0f * r2;
    float s = sqrt(fmax(0.0f, 1.0f - z * z));
    return (float3)(COS_TURNS(r1) * s, SIN_TURNS(r1) * s, z);
}

/* cos^n lobe around z, the report's eq. (4); its pdf is (n + 1) / (2 pi) cos^n(alpha).
 * cos(alpha) = r2^(1/(n+1)) is computed as exp(log(r2') / (n + 1)) with r2' = 1 - r2 (the same
 * distribution), so that r2 = 0 never reaches log and large n keeps precision. */
float3 sample_cosine_power(float r1, float r2, float n)
{
    float cos_a = exp(log(1.0f - r2) / (n + 1.0f));
    float sin_a = sqrt(max(0.0f, 1.0f - cos_a * cos_a));
    return (float3)(COS_TURNS(r1) * sin_a, SIN_TURNS(r1) * sin_a, cos_a);
}

float pdf_cosine_power(float cos_a, float n)
{
    /* cos_a from a rounded dot product can exceed 1, and 1.0000001^1e8 is 1.6e5 */
    return cos_a > 0.0f ? (n + 1.0f) / (2.0f * PI_F) * pow(min(cos_a, 1.0f), n) : 0.0f;
}

/* The unit disk, uniformly, by Shirley and Chiu's concentric map ("A Low Distortion Map
 * Between Disk and Square", 1997), in the form of pbrt-v4's SampleUniformDiskConcentric. */
float2 sample_concentric_disk(float2 u)
{
    float2 o = 2.0f * u - 1.0f;
    if (o.x == 0.0f && o.y == 0.0f)
        return (float2)(0.0f);
    float r, theta;                            /* in turns */
    if (fabs(o.x) > fabs(o.y)) {
        r = o.x;
        theta = 0.125f * (o.y / o.x);
    } else {
        r = o.y;
        theta = 0.25f - 0.125f * (o.x / o.y);
    }
    return r * (float2)(COS_TURNS(theta), SIN_TURNS(theta));
}

/* Power heuristic with beta = 2 (Veach, "Robust Monte Carlo Methods for Light Transport
 * Simulation", 1997, section 9.2.4): the weight of the technique with density a. Written as
 * 1 / (1 + (b / a)^2), so that densities whose squares overflow float32 (a Phong lobe of
 * exponent 1e8 has a density of 1.6e7) give 0 or 1, never inf / inf. */
float mis_weight(float a, float b)
{
    float r = b / a;
    return a > 0.0f ? 1.0f / (1.0f + r * r) : 0.0f;
}
