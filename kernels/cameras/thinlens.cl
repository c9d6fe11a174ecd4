/* A perspective camera with a thin lens (app/camera.py; Mitsuba 3's `thinlens`, pbrt-v4's
 * `perspective` with `lensradius` and `focaldistance`): a program of its own, as its registers
 * would cost the pinhole's scenes occupancy (docs/performance.md).
 *
 *   p->eye       the lens's centre
 *   p->forward   the unit view direction
 *   p->right     the image's right and up, scaled by tan(fov / 2) times the aspect ratio, and
 *   p->up        by tan(fov / 2)
 *   p->lens.x    the aperture's radius
 *   p->lens.y    the distance along `forward` to the plane in focus
 *
 * A ray leaves from a point of the aperture (uniform on the disk) through the point where the
 * pinhole's ray meets the plane in focus, as Mitsuba 3 and pbrt-v4 do: points on that plane
 * stay sharp, others blur by their distance from it. */

CameraRay generate_thinlens_ray(const RenderParams *p, float sx, float sy, float2 u)
{
    float2 ndc = film_to_ndc(p, sx, sy);
    /* d has a unit component along `forward`, so eye + focus_distance d lies on the plane */
    float3 d = p->forward.xyz + ndc.x * p->right.xyz + ndc.y * p->up.xyz;
    float2 lens = p->lens.x * sample_concentric_disk(u);
    float3 o = p->eye.xyz + lens.x * unit(p->right.xyz) + lens.y * unit(p->up.xyz);
    CameraRay ray = {o, unit(p->eye.xyz + p->lens.y * d - o)};
    return ray;
}
