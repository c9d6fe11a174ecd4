/* The disk (pbrt-v4's Disk, pbrt-v4 section 6.4; Mitsuba 3's disk), in its object's space: the
 * part of the plane z = height between radii inner_radius and radius and angles 0 to phi_max,
 * facing +z. Parameters (kernels/shapes/analytic.cl, row 6): (radius, inner_radius, height,
 * phi_max in radians). Its (u, v) are pbrt-v4's: u = phi / phi_max, v = (radius - r) /
 * (radius - inner_radius), so v = 0 on the outer rim. It has no thickness: a ray in its plane
 * misses it. */

float2 disk_uv(const global float4 *f, float3 p)
{
    float4 q = f[6];
    float phi = atan2(p.y, p.x);
    phi = phi < 0.0f ? phi + 2.0f * PI_F : phi;
    return (float2)(phi / q.w, (q.x - length(p.xy)) / (q.x - q.y));
}

float intersect_disk(const global float4 *f, float3 o, float3 d, float t_max, float2 *uv)
{
    float4 q = f[6];
    if (d.z == 0.0f)
        return INFINITY;
    float t = (q.z - o.z) / d.z;
    if (!(t > 0.0f && t < t_max))
        return INFINITY;
    float3 p = (float3)(o.xy + t * d.xy, q.z);
    float r2 = dot(p.xy, p.xy);
    if (r2 > q.x * q.x || r2 < q.y * q.y)
        return INFINITY;
    *uv = disk_uv(f, p);
    return uv->x <= 1.0f ? t : INFINITY;
}

/* The point of parameters uv, exactly in the plane (its error lies along it: 0 across), the
 * normal +z and pbrt-v4's dp/du = phi_max (-y, x, 0), dp/dv = (inner_radius - radius)
 * (cos phi, sin phi, 0). */
void disk_point(const global float4 *f, float2 uv, float3 *p, float3 *error, float3 *n, float3 *dpdu, float3 *dpdv)
{
    float4 q = f[6];
    float phi = uv.x * q.w, r = q.x - uv.y * (q.x - q.y);
    float2 dir = (float2)(cos(phi), sin(phi));
    *p = (float3)(r * dir, q.z);
    *error = (float3)(0.0f);
    *n = (float3)(0.0f, 0.0f, 1.0f);
    *dpdu = q.w * (float3)(-p->y, p->x, 0.0f);
    *dpdv = (q.y - q.x) * (float3)(dir, 0.0f);
}

float disk_area(const global float4 *f)
{
    float4 q = f[6];
    return 0.5f * q.w * (q.x * q.x - q.y * q.y);
}

/* Parameters of a point uniform over the area: r^2 uniform in [inner_radius^2, radius^2]. */
float2 sample_disk(const global float4 *f, float2 u)
{
    float4 q = f[6];
    float r = sqrt(q.y * q.y + u.x * (q.x * q.x - q.y * q.y));
    return (float2)(u.y, (q.x - r) / (q.x - q.y));
}
