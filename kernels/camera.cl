/* The camera interface. A camera type (kernels/cameras/<name>.cl) maps a point on the film to a
 * ray,
 *
 *   generate_X_ray(p, sx, sy, u)   the ray through film point (sx, sy), in pixels from the
 *                                  image's top-left corner, and lens point u in [0, 1)^2
 *
 * and a pixel filter (kernels/filters/<name>.cl) says where in and around a pixel its samples
 * fall,
 *
 *   sample_X_filter(p, u, rng)     an offset from the pixel's centre, distributed as the
 *                                  filter's weights, from two uniforms (and the rng, for a
 *                                  filter that rejects)
 *
 * Filter importance sampling (pbrt-v4, section 8.8): each sample lands where the filter says,
 * with weight 1, so that a pixel's samples stay independent and averaging them, as the
 * accumulation and the merge of several devices do, gives the filtered image. A program has one
 * camera type and one filter (app/features.py), named by the generated generate_ray and
 * sample_filter (app/camera.py, app/filters.py). */

typedef struct {
    float3 o;
    float3 d;    /* unit */
} CameraRay;

CameraRay generate_ray(const RenderParams *p, float sx, float sy, float2 u);
float2 sample_filter(const RenderParams *p, float2 u, Rng *rng);

/* The camera ray of pixel (x, y) for one sample: the first four uniforms of its rng place it
 * in the pixel (by the filter) and on the lens. */
CameraRay sample_camera_ray(const RenderParams *p, int x, int y, Rng *rng)
{
    float4 u = next_uniform4(rng);
    float2 offset = sample_filter(p, u.xy, rng);
    /* the offset from the centre first, then the pixel: the other order costs NVIDIA's compiler
       registers (docs/notes/performance-2026-11.md, 2026-11-24: lights, cameras and pixel filters) */
    return generate_ray(p, (float)x + (0.5f + offset.x), (float)y + (0.5f + offset.y), u.zw);
}

/* Film point (sx, sy) in pixels as the image's normalised coordinates, each in [-1, 1], +y up. */
float2 film_to_ndc(const RenderParams *p, float sx, float sy)
{
    return (float2)(2.0f * sx / p->width - 1.0f, 1.0f - 2.0f * sy / p->height);
}
