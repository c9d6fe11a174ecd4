/* Kernels of docs/notes/studies/simd_study.py: one diffuse bounce among five spheres under a white sky, in
 * three shapes, to see which of them PoCL runs in SIMD lanes. Each path's state is a structure
 * of arrays of n floats (origin, direction, throughput, radiance), so that consecutive paths lie
 * in consecutive words; random numbers are a hash of (path, dimension), as in kernels/rng.cl.
 *
 *   bounce        one path per work-item, in scalar floats: PoCL may vectorise its work-item
 *                 loop (the loop over a work-group's items) where LLVM's loop vectorizer can
 *   bounce_lanes  LANES paths per work-item, held in OpenCL vectors (floatN: one lane a path),
 *                 which PoCL compiles to SSE, AVX or AVX-512 instructions as written
 *   render        the whole path (DEPTH bounces) in one kernel, the megakernel's shape; with
 *                 BOUNCE_BARRIER a work-group barrier at each bounce, so that every bounce is a
 *                 parallel region of its own (PoCL's work-item loop inside the bounce loop)
 *
 * All three draw the same random numbers and compute the same sums, so their radiance agrees. */

#define SPHERES 5
constant float SX[SPHERES] = {0.0f, 0.0f, 2.2f, -2.2f, 0.0f};
constant float SY[SPHERES] = {-1000.0f, 0.0f, 0.0f, 0.0f, 3.0f};
constant float SZ[SPHERES] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
constant float SR[SPHERES] = {999.0f, 1.0f, 1.0f, 1.0f, 0.5f};
constant float ALBEDO[SPHERES] = {0.7f, 0.8f, 0.2f, 0.3f, 0.9f};

#define RAY_EPSILON 1e-3f

/* The body of a bounce, for T = float (one path) or floatN (LANES paths), I its integer type:
 * the nearest sphere (unrolled, selects only), then a cosine-weighted direction about its normal
 * (Duff et al. 2017's frame), the sky's radiance added where the ray escapes. */
#define BOUNCE(T, I, SELECT, ox, oy, oz, dx, dy, dz, tr, radiance, u1, u2)                     \
    {                                                                                           \
        T t_min = INFINITY, kx = 0.0f, ky = 0.0f, kz = 0.0f, ka = 0.0f;                         \
        _Pragma("unroll") for (int s = 0; s < SPHERES; ++s) {                                   \
            T cx = ox - SX[s], cy = oy - SY[s], cz = oz - SZ[s];                                \
            T b = cx * dx + cy * dy + cz * dz, h = b * b - (cx * cx + cy * cy + cz * cz - SR[s] * SR[s]); \
            T q = sqrt(fmax(h, 0.0f));                                                          \
            T t = SELECT(-b - q, -b + q, -b - q < RAY_EPSILON);                                 \
            t = SELECT(t, (T)(INFINITY), (h < 0.0f) | (t < RAY_EPSILON));                      \
            I closer = t < t_min;                                                               \
            kx = SELECT(kx, (T)(SX[s]), closer); ky = SELECT(ky, (T)(SY[s]), closer);           \
            kz = SELECT(kz, (T)(SZ[s]), closer); ka = SELECT(ka, (T)(ALBEDO[s]), closer);       \
            t_min = fmin(t, t_min);                                                             \
        }                                                                                       \
        I miss = t_min == INFINITY;                                                             \
        T px = ox + t_min * dx, py = oy + t_min * dy, pz = oz + t_min * dz;                     \
        T nx = px - kx, ny = py - ky, nz = pz - kz, inv = rsqrt(nx * nx + ny * ny + nz * nz);   \
        nx *= inv; ny *= inv; nz *= inv;                                                        \
        T r = sqrt(u1), phi = u2 * 2.0f - 1.0f, c = r * cospi(phi), sn = r * sinpi(phi);        \
        T sg = copysign((T)(1.0f), nz), a = -1.0f / (sg + nz), bb = nx * ny * a, z = sqrt(1.0f - u1); \
        radiance += SELECT((T)(0.0f), tr, miss);                                                \
        tr = SELECT(tr * ka, (T)(0.0f), miss);                                                  \
        dx = c * (1.0f + sg * nx * nx * a) + sn * bb + z * nx;                                  \
        dy = c * (sg * bb) + sn * (sg + ny * ny * a) + z * ny;                                  \
        dz = c * (-sg * nx) - sn * ny + z * nz;                                                 \
        ox = px + RAY_EPSILON * nx; oy = py + RAY_EPSILON * ny; oz = pz + RAY_EPSILON * nz;     \
    }

#define SCALAR_SELECT(a, b, c) ((c) ? (b) : (a))

uint hash(uint x)
{
    x ^= x >> 16; x *= 0x7feb352dU; x ^= x >> 15; x *= 0x846ca68bU; x ^= x >> 16;
    return x;
}

float uniform(uint path, uint dim)
{
    return (hash(path * 9781u + hash(dim)) >> 8) * (1.0f / 16777216.0f);
}

kernel void bounce(global float *o, global float *d, global float *tr, global float *radiance,
                   int n, int depth)
{
    int i = get_global_id(0);
    float ox = o[i], oy = o[n + i], oz = o[2 * n + i], dx = d[i], dy = d[n + i], dz = d[2 * n + i];
    float t = tr[i], l = radiance[i];
    float u1 = uniform(i, 2 * depth), u2 = uniform(i, 2 * depth + 1);
    BOUNCE(float, int, SCALAR_SELECT, ox, oy, oz, dx, dy, dz, t, l, u1, u2);
    o[i] = ox; o[n + i] = oy; o[2 * n + i] = oz;
    d[i] = dx; d[n + i] = dy; d[2 * n + i] = dz;
    tr[i] = t; radiance[i] = l;
}

#ifdef LANES
uintN hash_lanes(uintN x)
{
    x ^= x >> 16; x *= 0x7feb352dU; x ^= x >> 15; x *= 0x846ca68bU; x ^= x >> 16;
    return x;
}

floatN uniform_lanes(uintN path, uint dim)
{
    return convert_floatN(hash_lanes(path * 9781u + hash(dim)) >> 8) * (1.0f / 16777216.0f);
}

kernel void bounce_lanes(global float *o, global float *d, global float *tr, global float *radiance,
                         int n, int depth)
{
    int i = get_global_id(0) * LANES;
    uintN path = as_uintN((intN)(i) + LANE_INDEX);
    floatN ox = VLOAD(0, o + i), oy = VLOAD(0, o + n + i), oz = VLOAD(0, o + 2 * n + i);
    floatN dx = VLOAD(0, d + i), dy = VLOAD(0, d + n + i), dz = VLOAD(0, d + 2 * n + i);
    floatN t = VLOAD(0, tr + i), l = VLOAD(0, radiance + i);
    floatN u1 = uniform_lanes(path, 2 * depth), u2 = uniform_lanes(path, 2 * depth + 1);
    BOUNCE(floatN, intN, select, ox, oy, oz, dx, dy, dz, t, l, u1, u2);
    VSTORE(ox, 0, o + i); VSTORE(oy, 0, o + n + i); VSTORE(oz, 0, o + 2 * n + i);
    VSTORE(dx, 0, d + i); VSTORE(dy, 0, d + n + i); VSTORE(dz, 0, d + 2 * n + i);
    VSTORE(t, 0, tr + i); VSTORE(l, 0, radiance + i);
}
#endif

#ifdef DEPTH
kernel void render(const global float *o, const global float *d, global float *radiance, int n)
{
    int i = get_global_id(0);
    float ox = o[i], oy = o[n + i], oz = o[2 * n + i], dx = d[i], dy = d[n + i], dz = d[2 * n + i];
    float t = 1.0f, l = 0.0f;
    for (int depth = 0; depth < DEPTH; ++depth) {
#ifdef BOUNCE_BARRIER
        barrier(CLK_LOCAL_MEM_FENCE);
#endif
        float u1 = uniform(i, 2 * depth), u2 = uniform(i, 2 * depth + 1);
        BOUNCE(float, int, SCALAR_SELECT, ox, oy, oz, dx, dy, dz, t, l, u1, u2);
    }
    radiance[i] = l;
}
#endif
