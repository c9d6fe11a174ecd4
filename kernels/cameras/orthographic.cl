/* An orthographic camera (app/cameras/orthographic.py; Mitsuba 3's and pbrt-v4's `orthographic`): parallel
 * rays along the view direction from the points of a rectangle.
 *
 *   p->eye       the rectangle's centre
 *   p->forward   the unit view direction
 *   p->right     the rectangle's half width and half height, in world units, along the image's
 *   p->up        right and up */

CameraRay generate_orthographic_ray(const RenderParams *p, float sx, float sy, float2 u)
{
    float2 ndc = film_to_ndc(p, sx, sy);
    CameraRay ray = {p->eye.xyz + ndc.x * p->right.xyz + ndc.y * p->up.xyz, p->forward.xyz};
    return ray;
}
