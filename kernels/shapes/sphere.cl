/* The sphere (pbrt-v4's Sphere, pbrt-v4 section 6.2; Mitsuba 3's sphere), in its object's space:
 * the points at distance radius from the origin with z_min <= z <= z_max and angles 0 to
 * phi_max; its normal points away from the centre. Under a transform that stretches unevenly it
 * is an ellipsoid, as pbrt-v4's is. Parameters (kernels/shapes/analytic.cl, row 6): (radius,
 * z_min, z_max, phi_max in radians), z_min and z_max within [-radius, radius]. Its (u, v) are
 * pbrt-v4's: u = phi / phi_max, v = (theta - theta_zmin) / (theta_zmax - theta_zmin), theta the
 * angle from +z, so v = 0 at z_min (Mitsuba's v = theta / pi is pbrt's whole sphere with z
 * turned round: app/shapes/sphere.py). */

/* The angle from +z of the points at height z, as atan2 of the ring's radius: acos(z / r)
 * loses its precision near the poles. */
float sphere_theta(float r, float z)
{
    return atan2(sqrt(max(0.0f, (r - z) * (r + z))), z);
}

/* (theta_zmin, theta_zmax): pi and 0 for the whole height. */
float2 sphere_theta_range(float4 q)
{
    return (float2)(q.y <= -q.x ? PI_F : sphere_theta(q.x, q.y), q.z >= q.x ? 0.0f : sphere_theta(q.x, q.z));
}

float2 sphere_uv(const global float4 *f, float3 p)
{
    float4 q = f[6];
    float phi = atan2(p.y, p.x);
    phi = phi < 0.0f ? phi + 2.0f * PI_F : phi;
    float2 range = sphere_theta_range(q);
    float theta = atan2(sqrt(p.x * p.x + p.y * p.y), p.z);
    return (float2)(phi / q.w, (theta - range.x) / (range.y - range.x));
}

/* The nearer of the two crossings within the ray's (0, t_max) whose point lies in the sphere's
 * z range and angle (pbrt-v4's Sphere::BasicIntersect tests the far one where the near one is
 * cut away). The crossings are the sphere range's (kernels/shapes/sphere_range.cl), of the
 * direction made unit: d stays unnormalised in the object's space, so that t is the world's. */
float intersect_sphere(const global float4 *f, float3 o, float3 d, float t_max, float2 *uv)
{
    float4 q = f[6];
    float inv_length = rsqrt(dot(d, d));
    float2 t = sphere_crossings((float4)(0.0f, 0.0f, 0.0f, q.x), o, d * inv_length) * inv_length;
    for (int k = 0; k < 2; ++k) {
        float tk = k == 0 ? t.x : t.y;
        if (!(tk > 0.0f && tk < t_max))
            continue;
        float3 p = o + tk * d;
        /* as pbrt-v4, a z bound at a pole cuts nothing: a point rounded past it stays */
        if ((q.y > -q.x && p.z < q.y) || (q.z < q.x && p.z > q.z))
            continue;
        float2 h = sphere_uv(f, p);
        if (h.x <= 1.0f) {
            *uv = h;
            return tk;
        }
    }
    return INFINITY;
}

/* The point of parameters uv on the sphere, its error bound, the outward normal and pbrt-v4's
 * dp/du = phi_max (-y, x, 0), dp/dv = (theta_zmax - theta_zmin) (z cos phi, z sin phi,
 * -r sin theta). The point is r (sin theta cos phi, sin theta sin phi, cos theta): each
 * coordinate a product of two of OpenCL's sin and cos (4 ulp each, OpenCL 1.2 section 7.4) and
 * the radius, within 9 ulp of its value, gamma(18) of it. A point moved along the angles stays
 * on the sphere, so the error of the angles read from a hit moves it along the surface only. */
void sphere_point(const global float4 *f, float2 uv, float3 *p, float3 *error, float3 *n, float3 *dpdu,
                  float3 *dpdv)
{
    float4 q = f[6];
    float2 range = sphere_theta_range(q);
    float theta = range.x + uv.y * (range.y - range.x), phi = uv.x * q.w;
    float sin_theta = sin(theta), cos_theta = cos(theta);
    float2 dir = (float2)(cos(phi), sin(phi));
    *n = (float3)(sin_theta * dir, cos_theta);
    *p = q.x * *n;
    *error = gamma_bound(18) * fabs(*p);
    *dpdu = q.w * (float3)(-p->y, p->x, 0.0f);
    *dpdv = (range.y - range.x) * (float3)(p->z * dir, -q.x * sin_theta);
}

float sphere_area(const global float4 *f)
{
    float4 q = f[6];
    return q.w * q.x * (q.z - q.y);
}

/* Parameters of a point uniform over the area: z uniform in [z_min, z_max] (Archimedes: a
 * zone's area is 2 pi r times its height) and phi uniform. pbrt-v4's Sphere::Sample(u) samples
 * the whole sphere whatever z_min, z_max and phi_max. */
float2 sample_sphere(const global float4 *f, float2 u)
{
    float4 q = f[6];
    float2 range = sphere_theta_range(q);
    float theta = sphere_theta(q.x, q.y + u.y * (q.z - q.y));
    return (float2)(u.x, (theta - range.x) / (range.y - range.x));
}
