/* Counter-based random numbers: every number is a hash of (pixel, sample index, seed, dimension),
 * so a render is reproducible for a seed whatever the work-group layout or launch split.
 * The hash is pcg4d of Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT 9(3), 2020,
 * which passes TestU01's BigCrush as a 4-in/4-out hash. */

typedef struct {
    uint4 key;   /* pixel x, pixel y, sample index, seed */
    uint dim;    /* how many blocks of four dimensions were drawn so far */
} Rng;

uint4 pcg4d(uint4 v)
{
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    return v;
}

Rng make_rng(uint x, uint y, uint sample, uint seed)
{
    Rng rng;
    rng.key = (uint4)(x, y, sample, pcg4d((uint4)(seed, 0u, 0u, 0u)).x);
    rng.dim = 0u;
    return rng;
}

/* The next four 32-bit hash words. */
uint4 next_bits4(Rng *rng)
{
    uint4 v = rng->key;
    v.w += 0x9e3779b9u * rng->dim++;
    return pcg4d(v);
}

/* Four uniform numbers in [0, 1) from four hash words: the top 24 bits of each (a float's
 * precision), so 1 is never returned. */
float4 to_uniform4(uint4 bits)
{
    return convert_float4(bits >> 8u) * 0x1.0p-24f;
}

float4 next_uniform4(Rng *rng)
{
    return to_uniform4(next_bits4(rng));
}
