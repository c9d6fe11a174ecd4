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
 * camera type and one filter (app/device/features.py), named by the generated generate_ray and
 * sample_filter (app/cameras/registry.py, app/filters.py). */

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

#ifdef BDPT
/* The camera's importance, for light subpaths that reach it (kernels/bdpt.cl), in the conventions
 * of pbrt-v4's PerspectiveCamera (cameras.cpp: We, PDF_We, SampleWi), for the pinhole and the
 * thin lens: the film is the plane one unit ahead, of area A = 4 |right| |up|, and a camera ray of
 * direction d at angle theta from `forward` has density 1 / (A cos^3 theta) per solid angle
 * (pixel and filter offset uniform over the film), its importance being
 * We = 1 / (A cos^4 theta) over the lens's area. Each camera type provides
 *
 *   sample_X_importance(p, x, u, &ci)   a point of its lens joined to point x, from two uniforms
 *
 * and sample_importance (app/cameras/registry.py) calls the program's; a camera type without it
 * (Camera.importance False) is refused by app/rendering/bdpt.py. */
typedef struct {
    float3 lens;     /* the lens point joined to x */
    float2 at;       /* the film point, in pixels from the image's top-left corner */
    float weight;    /* We cos_lens / (dist^2 pdf_lens): what light arriving at the lens from x
                        adds to the film (times the filter's density, kernels/bdpt.cl: splat) */
} CameraImportance;

int sample_importance(const RenderParams *p, float3 x, float2 u, CameraImportance *ci);

/* The area of the film at unit distance. */
float film_area(const RenderParams *p)
{
    return 4.0f * norm(p->right.xyz) * norm(p->up.xyz);
}

/* The density per solid angle of camera rays along unit direction d (0 behind the camera). */
float pdf_camera_direction(const RenderParams *p, float3 d)
{
    float c = dot(d, p->forward.xyz);
    return c > 0.0f ? 1.0f / (film_area(p) * c * c * c) : 0.0f;
}

/* Where unit direction d from the eye crosses the film, in pixels (the inverse of the pinhole's
 * ray); 0 behind. */
int film_point(const RenderParams *p, float3 d, float2 *at)
{
    float c = dot(d, p->forward.xyz);
    if (!(c > 0.0f))
        return 0;
    float3 q = d / c;
    float x = dot(q, p->right.xyz) / dot(p->right.xyz, p->right.xyz);
    float y = dot(q, p->up.xyz) / dot(p->up.xyz, p->up.xyz);
    *at = (float2)(0.5f * (x + 1.0f) * p->width, 0.5f * (1.0f - y) * p->height);
    return 1;
}

/* Lens point o joined to point x: the film point of the ray from o towards x as a pinhole at o
 * sees it, and We cos / (dist^2 pdf_lens) = 1 / (A cos^3 dist^2) (the lens's area cancels). */
int join_camera(const RenderParams *p, float3 o, float3 x, CameraImportance *ci)
{
    float3 w = x - o;
    float d2 = dot(w, w);
    float3 d = w * rsqrt(d2);
    float c = dot(d, p->forward.xyz);
    if (!(d2 > 0.0f) || !film_point(p, d, &ci->at))
        return 0;
    ci->lens = o;
    ci->weight = 1.0f / (film_area(p) * c * c * c * d2);
    return 1;
}
#endif

