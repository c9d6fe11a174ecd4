/* bitmap: an image looked up at uv (Mitsuba 3's `bitmap`, pbrt-v4's `imagemap`).
 *
 * Fields (Texture):
 *   width, height   the image's size in texels. Texel (x, y) covers [x, x + 1] / width by
 *                   [y, y + 1] / height in uv, row y = 0 being the image file's first (top)
 *                   row: uv (0, 0) is the file's top-left corner, as in Mitsuba 3 (whose OBJ
 *                   reader, like app/scene/meshes.py, flips the format's v to match).
 *   texels          the first texel, in 4-byte words of the texel buffer; rows of width texels
 *                   of `channels` values each (1: grey; 4: rgba, an rgb image's fourth value
 *                   being padding and an rgba image's alpha unused here), top row first
 *   format          TEXELS_SRGB8: 8-bit sRGB-encoded values, decoded to linear through the
 *                   table of 256 floats at the start of the texel buffer (global memory, whose
 *                   cache serves a GPU warp's differing indices at once, where constant memory
 *                   serialises them); TEXELS_LINEAR8: 8-bit values v / 255 (Mitsuba's raw, pbrt's
 *                   encoding "linear"); TEXELS_HALF and TEXELS_FLOAT: linear 16- and 32-bit floats
 *   wrap            WRAP_REPEAT, WRAP_MIRROR or WRAP_CLAMP: the texel of a coordinate beyond the
 *                   image (Mitsuba's wrap_mode)
 *   filter          FILTER_NEAREST: the texel under uv; FILTER_BILINEAR: the four texels whose
 *                   centres surround uv, weighted bilinearly (Mitsuba's filter_type)
 *   to_u, to_v      the uv transform (Mitsuba's to_uv)
 */

#define TEXELS_SRGB8 0
#define TEXELS_LINEAR8 1
#define TEXELS_HALF 2
#define TEXELS_FLOAT 3

#define WRAP_REPEAT 0
#define WRAP_MIRROR 1
#define WRAP_CLAMP 2

#define FILTER_NEAREST 0
#define FILTER_BILINEAR 1

/* A texel coordinate x of an image n texels wide brought into [0, n) by the wrap mode. x lies
 * in [-1, 2n]: eval_bitmap first brings uv into one period of the wrap in floating point, so
 * that no integer division is needed, which is slow on GPUs (docs/notes/performance-2026-11.md, 2026-11-24:
 * textures). */
int wrap_texel(int x, int n, int wrap)
{
    if (wrap == WRAP_CLAMP)
        return clamp(x, 0, n - 1);
    if (wrap == WRAP_MIRROR) {
        int m = x < 0 ? x + 2 * n : (x >= 2 * n ? x - 2 * n : x);
        return m < n ? m : 2 * n - 1 - m;
    }
    return x < 0 ? x + n : (x >= n ? x - n : x);
}

/* Texel i of an image of `channels` values per texel (1 or 4) as rgb, in one aligned load (an
 * rgb image is stored as rgba: a quarter more memory than three separate loads of its values
 * take, for one branch-free load, which was no slower: docs/notes/performance-2026-11.md, 2026-11-24:
 * textures). */
float3 read_texel(const SceneData *sc, const global Texture *t, size_t i)
{
    const global uchar *texels = sc->texels + (size_t)t->texels * 4;
    const global float *srgb = (const global float *)sc->texels;
    if (t->channels == 1) {
        switch (t->format) {
        case TEXELS_SRGB8: return (float3)(srgb[texels[i]]);
        case TEXELS_LINEAR8: return (float3)(texels[i] * (1.0f / 255.0f));
        case TEXELS_HALF: return (float3)(vload_half(i, (const global half *)texels));
        default: return (float3)(((const global float *)texels)[i]);
        }
    }
    switch (t->format) {
    case TEXELS_SRGB8: {
        uchar4 c = ((const global uchar4 *)texels)[i];
        return (float3)(srgb[c.x], srgb[c.y], srgb[c.z]);
    }
    case TEXELS_LINEAR8: return convert_float4(((const global uchar4 *)texels)[i]).xyz * (1.0f / 255.0f);
    case TEXELS_HALF: return vload_half4(i, (const global half *)texels).xyz;
    default: return ((const global float4 *)texels)[i].xyz;
    }
}

/* A texel coordinate as a float brought into the range of int. */
int texel_coordinate(float x)
{
    return (int)floor(clamp(x, -1.0e9f, 1.0e9f));
}

/* uv made finite (a NaN 0, beyond +-1e9 clamped), so that any uv looks up some texel, then
 * brought into one period of the wrap mode: [0, 1] for repeat, [0, 2] for mirror (a rounded
 * end of the range is one texel beyond, which wrap_texel takes). */
float2 wrap_period(float2 st, int wrap)
{
    st = clamp(select(st, (float2)(0.0f), isnan(st)), -1.0e9f, 1.0e9f);
    if (wrap == WRAP_REPEAT)
        return st - floor(st);
    if (wrap == WRAP_MIRROR)
        return st - 2.0f * floor(0.5f * st);
    return st;
}

/* The four texels whose centres (at half-integer coordinates) surround uv, each coordinate
 * wrapped once: their indices 00, 10, 01, 11 (x first), and uv's bilinear weights (ax, ay)
 * between them. */
void bilinear_texels(const global Texture *t, float2 uv, ulong4 *texel, float2 *a)
{
    int w = t->width, h = t->height;
    float x = uv.x * w - 0.5f, y = uv.y * h - 0.5f;
    int x0 = texel_coordinate(x), y0 = texel_coordinate(y);
    *a = (float2)(x - floor(x), y - floor(y));
    int x1 = wrap_texel(x0 + 1, w, t->wrap), y1 = wrap_texel(y0 + 1, h, t->wrap);
    x0 = wrap_texel(x0, w, t->wrap);
    y0 = wrap_texel(y0, h, t->wrap);
    size_t row0 = (size_t)y0 * w, row1 = (size_t)y1 * w;
    *texel = (ulong4)(row0 + x0, row0 + x1, row1 + x0, row1 + x1);
}

float3 eval_bitmap(const SceneData *sc, const global Texture *t, float2 uv)
{
    LOG_TEXTURE_LOOKUP(sc);      /* the divergence stats build counts lookups (kernels/divergence.cl) */
    uv = wrap_period(transform_uv(t, uv), t->wrap);
    if (t->filter == FILTER_NEAREST) {
        int x = wrap_texel(texel_coordinate(uv.x * t->width), t->width, t->wrap);
        int y = wrap_texel(texel_coordinate(uv.y * t->height), t->height, t->wrap);
        return read_texel(sc, t, (size_t)y * t->width + x);
    }
    ulong4 i;
    float2 a;
    bilinear_texels(t, uv, &i, &a);
    float3 top = mix(read_texel(sc, t, i.s0), read_texel(sc, t, i.s1), a.x);
    float3 bottom = mix(read_texel(sc, t, i.s2), read_texel(sc, t, i.s3), a.x);
    return mix(top, bottom, a.y);
}

/* The gradient of the bitmap's luminance with respect to the surface's uv, as Mitsuba 3's
 * eval_1_grad: the bilinear interpolant's partial derivatives in texels, times the resolution,
 * through the transpose of the uv transform's linear part; 0 for nearest filtering, whose
 * value is piecewise constant (a bump map's slopes, kernels/normal_maps.cl). */
float2 grad_bitmap(const SceneData *sc, const global Texture *t, float2 uv)
{
    LOG_TEXTURE_LOOKUP(sc);
    if (t->filter == FILTER_NEAREST)
        return (float2)(0.0f);
    ulong4 i;
    float2 a;
    bilinear_texels(t, wrap_period(transform_uv(t, uv), t->wrap), &i, &a);
    float f00 = luminance(read_texel(sc, t, i.s0)), f10 = luminance(read_texel(sc, t, i.s1));
    float f01 = luminance(read_texel(sc, t, i.s2)), f11 = luminance(read_texel(sc, t, i.s3));
    float2 df = (float2)((1.0f - a.y) * (f10 - f00) + a.y * (f11 - f01),
                         (1.0f - a.x) * (f01 - f00) + a.x * (f11 - f10)) * (float2)(t->width, t->height);
    return (float2)(t->to_u.x * df.x + t->to_v.x * df.y, t->to_u.y * df.x + t->to_v.y * df.y);
}
