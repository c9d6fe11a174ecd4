/* The cylinder (pbrt-v4's Cylinder, pbrt-v4 section 6.3; Mitsuba 3's cylinder), in its object's
 * space: the points at distance radius from the z axis with z_min <= z <= z_max and angles 0 to
 * phi_max, without caps; its normal points away from the axis. Parameters
 * (kernels/shapes/analytic.cl, row 6): (radius, z_min, z_max, phi_max in radians). Its (u, v)
 * are pbrt-v4's: u = phi / phi_max, v = (z - z_min) / (z_max - z_min) (Mitsuba's too, whose
 * cylinder is pbrt's of radius 1, z in [0, 1] and a whole turn under its frame). */

float2 cylinder_uv(const global float4 *f, float3 p)
{
    float4 q = f[6];
    float phi = atan2(p.y, p.x);
    phi = phi < 0.0f ? phi + 2.0f * PI_F : phi;
    return (float2)(phi / q.w, (p.z - q.y) / (q.z - q.y));
}

/* The nearer of the two crossings of the infinite cylinder within the ray's (0, t_max) whose
 * point lies in the cylinder's z range and angle. The roots of |o.xy + t d.xy|^2 = r^2 are
 * taken as c / s and s / a with the discriminant r^2 a - (o x d).z^2 (Lagrange's identity), as
 * kernels/shapes/sphere_range.cl takes a sphere's (Haines et al., Ray Tracing Gems, ch. 7): both stay
 * accurate for a thin cylinder seen from afar. */
float intersect_cylinder(const global float4 *f, float3 o, float3 d, float t_max, float2 *uv)
{
    float4 q = f[6];
    float a = d.x * d.x + d.y * d.y;
    float b = o.x * d.x + o.y * d.y;
    float cross_z = o.x * d.y - o.y * d.x;
    float disc = q.x * q.x * a - cross_z * cross_z;
    if (a == 0.0f || disc < 0.0f)
        return INFINITY;
    float c = o.x * o.x + o.y * o.y - q.x * q.x;
    float s = -(b + copysign(sqrt(disc), b));
    float t0 = c / s, t1 = s / a;
    float2 t = (float2)(fmin(t0, t1), fmax(t0, t1));
    for (int k = 0; k < 2; ++k) {
        float tk = k == 0 ? t.x : t.y;
        if (!(tk > 0.0f && tk < t_max))
            continue;
        float2 h = cylinder_uv(f, o + tk * d);
        if (h.x <= 1.0f && h.y >= 0.0f && h.y <= 1.0f) {
            *uv = h;
            return tk;
        }
    }
    return INFINITY;
}

/* The point of parameters uv on the cylinder, its error bound (the rounding of r cos(phi) and
 * r sin(phi), across the surface; pbrt-v4 bounds its reprojected point by gamma(3) |(x, y)|,
 * here cos and sin add their 4 ulp), the outward normal and pbrt-v4's dp/du = phi_max (-y, x, 0),
 * dp/dv = (0, 0, z_max - z_min). */
void cylinder_point(const global float4 *f, float2 uv, float3 *p, float3 *error, float3 *n, float3 *dpdu,
                    float3 *dpdv)
{
    float4 q = f[6];
    float phi = uv.x * q.w;
    float2 dir = (float2)(cos(phi), sin(phi));
    *p = (float3)(q.x * dir, q.y + uv.y * (q.z - q.y));
    *error = gamma_bound(7) * fabs((float3)(p->xy, 0.0f));
    *n = (float3)(dir, 0.0f);
    *dpdu = q.w * (float3)(-p->y, p->x, 0.0f);
    *dpdv = (float3)(0.0f, 0.0f, q.z - q.y);
}

float cylinder_area(const global float4 *f)
{
    float4 q = f[6];
    return (q.z - q.y) * q.x * q.w;
}

/* Parameters of a point uniform over the area: u and v uniform. */
float2 sample_cylinder(const global float4 *f, float2 u)
{
    return u;
}
