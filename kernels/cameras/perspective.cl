/* A perspective camera (app/camera.py): a pinhole, or a thin lens (Mitsuba 3's `thinlens`,
 * pbrt-v4's `perspective` with `lensradius` and `focaldistance`).
 *
 *   p->eye       the centre of projection (of the lens)
 *   p->forward   the unit view direction
 *   p->right     the image's right and up, scaled by tan(fov / 2) times the aspect ratio, and
 *   p->up        by tan(fov / 2)
 *   p->lens.x    the aperture's radius (0: a pinhole)
 *   p->lens.y    the distance along `forward` to the plane in focus
 *
 * A thin lens sends the ray from a point of its aperture (uniform on the disk) through the point
 * where the pinhole's ray meets the plane in focus, as Mitsuba 3 and pbrt-v4 do: points on that
 * plane stay sharp, others blur by their distance from it. */

CameraRay generate_perspective_ray(const RenderParams *p, float sx, float sy, float2 u)
{
    float2 ndc = film_to_ndc(p, sx, sy);
    float3 d = p->forward.xyz + ndc.x * p->right.xyz + ndc.y * p->up.xyz;
    CameraRay ray = {p->eye.xyz, d};
    if (p->lens.x > 0.0f) {
        /* d has a unit component along `forward`, so eye + focus_distance d lies on the plane */
        float2 lens = p->lens.x * sample_concentric_disk(u);
        ray.o += lens.x * unit(p->right.xyz) + lens.y * unit(p->up.xyz);
        d = p->eye.xyz + p->lens.y * d - ray.o;
    }
    ray.d = unit(d);
    return ray;
}
