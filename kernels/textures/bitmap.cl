/* bitmap: an image looked up at uv (Mitsuba 3's `bitmap`, pbrt-v4's `imagemap`).
 *
 * Fields (Texture):
 *   width, height   the image's size in texels. Texel (x, y) covers [x, x + 1] / width by
 *                   [y, y + 1] / height in uv, row y = 0 being the image file's first (top)
 *                   row: uv (0, 0) is the file's top-left corner, as in Mitsuba 3 (whose OBJ
 *                   reader, like app/scene/meshes.py, flips the format's v to match).
 *   texels          the first texel, in 4-byte words of the texel buffer; rows of width texels
 *                   of `channels` values each (1: grey, 3: rgb, 4: rgba, whose alpha is unused
 *                   here), top row first
 *   format          TEXELS_SRGB8: 8-bit sRGB-encoded values, decoded to linear through
 *                   SRGB_TO_LINEAR; TEXELS_LINEAR8: 8-bit values v / 255 (Mitsuba's raw, pbrt's
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

/* A texel coordinate x of an image n texels wide, brought into [0, n) by the wrap mode. */
int wrap_texel(int x, int n, int wrap)
{
    if (wrap == WRAP_CLAMP)
        return clamp(x, 0, n - 1);
    if (wrap == WRAP_MIRROR) {
        int m = x % (2 * n);
        m = m < 0 ? m + 2 * n : m;
        return m < n ? m : 2 * n - 1 - m;
    }
    int m = x % n;
    return m < 0 ? m + n : m;
}

float read_channel(const global uchar *texels, int format, size_t i)
{
    switch (format) {
    case TEXELS_SRGB8: return SRGB_TO_LINEAR[texels[i]];
    case TEXELS_LINEAR8: return texels[i] * (1.0f / 255.0f);
    case TEXELS_HALF: return vload_half(i, (const global half *)texels);
    default: return ((const global float *)texels)[i];
    }
}

/* The colour of texel (x, y), its coordinates wrapped. */
float3 fetch_texel(const SceneData *sc, const global Texture *t, int x, int y)
{
    x = wrap_texel(x, t->width, t->wrap);
    y = wrap_texel(y, t->height, t->wrap);
    const global uchar *texels = sc->texels + (size_t)t->texels * 4;
    size_t i = ((size_t)y * t->width + x) * t->channels;
    if (t->channels == 1)
        return (float3)(read_channel(texels, t->format, i));
    return (float3)(read_channel(texels, t->format, i), read_channel(texels, t->format, i + 1),
                    read_channel(texels, t->format, i + 2));
}

/* A texel coordinate as a float brought into the range of int (and a NaN to 0), so that any uv
 * the transform makes looks up some texel. */
float texel_coordinate(float x)
{
    return fmin(fmax(x, -1.0e9f), 1.0e9f);
}

float3 eval_bitmap(const SceneData *sc, const global Texture *t, float2 uv)
{
    uv = transform_uv(t, uv);
    float x = texel_coordinate(uv.x * t->width), y = texel_coordinate(uv.y * t->height);
    if (t->filter == FILTER_NEAREST)
        return fetch_texel(sc, t, (int)floor(x), (int)floor(y));
    /* texel centres lie at half-integer coordinates */
    x -= 0.5f;
    y -= 0.5f;
    float fx = floor(x), fy = floor(y);
    float ax = x - fx, ay = y - fy;
    int x0 = (int)fx, y0 = (int)fy;
    float3 top = mix(fetch_texel(sc, t, x0, y0), fetch_texel(sc, t, x0 + 1, y0), ax);
    float3 bottom = mix(fetch_texel(sc, t, x0, y0 + 1), fetch_texel(sc, t, x0 + 1, y0 + 1), ax);
    return mix(top, bottom, ay);
}
