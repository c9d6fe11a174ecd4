/* A perspective camera with a thin lens (app/cameras/thinlens.py; Mitsuba 3's `thinlens`, pbrt-v4's
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

#ifdef BDPT
/* Joins point x to a point of the aperture drawn uniformly from u (pbrt-v4's PerspectiveCamera::
 * SampleWi with a lens): the lens's area density 1 / (pi r^2) and its importance
 * 1 / (A pi r^2 cos^4) cancel their pi r^2 (kernels/camera.cl: join_camera), and the film point
 * is where the line from the lens point through x crosses the plane in focus, seen from the
 * lens's centre (the inverse of generate_thinlens_ray). */
int sample_thinlens_importance(const RenderParams *p, float3 x, float2 u, CameraImportance *ci)
{
    float2 lens = p->lens.x * sample_concentric_disk(u);
    float3 o = p->eye.xyz + lens.x * unit(p->right.xyz) + lens.y * unit(p->up.xyz);
    if (!join_camera(p, o, x, ci))
        return 0;
    float3 d = unit(x - o);
    float3 focus = o + (p->lens.y / dot(d, p->forward.xyz)) * d;
    return film_point(p, unit(focus - p->eye.xyz), &ci->at);
}
#endif

