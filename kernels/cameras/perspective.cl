/* A perspective camera with a pinhole (app/cameras/perspective.py; Mitsuba 3's `perspective`, pbrt-v4's
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
/* Joins point x to the pinhole (pbrt-v4's PerspectiveCamera::SampleWi): the eye is the only
 * point of its lens (kernels/camera.cl: CameraImportance). */
int sample_perspective_importance(const RenderParams *p, float3 x, float2 u, CameraImportance *ci)
{
    return join_camera(p, p->eye.xyz, x, ci);
}
#endif
