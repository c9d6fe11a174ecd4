/* A perspective camera with a pinhole (app/camera.py; Mitsuba 3's `perspective`, pbrt-v4's
 * `perspective` without a lens).
 *
 *   p->eye       the centre of projection
 *   p->forward   the unit view direction
 *   p->right     the image's right and up, scaled by tan(fov / 2) times the aspect ratio, and
 *   p->up        by tan(fov / 2)
 *
 * Every ray leaves from the eye, through the film point's place on the plane one unit ahead. */

CameraRay generate_perspective_ray(const RenderParams *p, float sx, float sy, float2 u)
{
    float2 ndc = film_to_ndc(p, sx, sy);
    CameraRay ray = {p->eye.xyz, unit(p->forward.xyz + ndc.x * p->right.xyz + ndc.y * p->up.xyz)};
    return ray;
}

#ifdef BDPT
/* The pinhole's importance, for light subpaths that reach it (kernels/bdpt.cl), in the
 * conventions of pbrt-v4's PerspectiveCamera (cameras.cpp: We, PDF_We, SampleWi): the film is
 * the plane one unit ahead, of area A = 4 |right| |up|, and a camera ray of direction d at angle
 * theta from `forward` has density 1 / (A cos^3 theta) per solid angle (pixel and filter offset
 * uniform over the film), its importance being We = 1 / (A cos^4 theta). */

/* The area of the film at unit distance. */
float perspective_film_area(const RenderParams *p)
{
    return 4.0f * norm(p->right.xyz) * norm(p->up.xyz);
}

/* The density per solid angle of camera rays along unit direction d from the eye (0 behind). */
float pdf_perspective_direction(const RenderParams *p, float3 d)
{
    float c = dot(d, p->forward.xyz);
    return c > 0.0f ? 1.0f / (perspective_film_area(p) * c * c * c) : 0.0f;
}

/* Where unit direction d from the eye crosses the film, in pixels from the image's top-left
 * corner (the inverse of generate_perspective_ray), with cos theta in *cos_t; 0 behind. */
int perspective_film_point(const RenderParams *p, float3 d, float2 *film, float *cos_t)
{
    float c = dot(d, p->forward.xyz);
    if (!(c > 0.0f))
        return 0;
    float3 q = d / c;
    float x = dot(q, p->right.xyz) / dot(p->right.xyz, p->right.xyz);
    float y = dot(q, p->up.xyz) / dot(p->up.xyz, p->up.xyz);
    *film = (float2)(0.5f * (x + 1.0f) * p->width, 0.5f * (1.0f - y) * p->height);
    *cos_t = c;
    return 1;
}
#endif
