/* The triangle: watertight intersection, the surface at a hit, and sampling points by area
 * (for next-event estimation on emissive meshes). */

/* Watertight ray-triangle intersection (Woop, Benthin & Wald, "Watertight Ray/Triangle
 * Intersection", JCGT 2(1), 2013). The triangle is moved into a space where the ray starts at
 * the origin and runs along +z (a translation, a permutation of the axes so that the ray's
 * largest component is z, and a shear); the 2D edge functions of the transformed corners then
 * decide the hit. A shared edge is computed from the same transformed corners by both of its
 * triangles, and each edge function has the sign of its exact value (edge_function), so the
 * two triangles see the ray on opposite sides of the edge, or on it, and it can never pass
 * between them.
 * The shear rows are passed in (see triangle_shear): they depend on the ray only.
 * Returns t in (0, t_max) or INFINITY, with the barycentric weights of v1 and v2. A ray never
 * tests the triangle it leaves (kernels/bvh.cl: `self`), so any t > 0 is a hit: a neighbour
 * met at t ~ 0 in a concave corner is met (a bound on t's rounding, as pbrt-v4 rejects below,
 * let such rays through the corners of a closed box). */
#pragma OPENCL FP_CONTRACT OFF
/* ax by - ay bx by Kahan's difference of products: the rounding error of ay bx, recovered
 * exactly by a fused multiply-add, is added back, which leaves the result within 2 ulp of the
 * exact value (Jeannerod, Louvet and Muller, "Further analysis of Kahan's algorithm for the
 * accurate computation of 2x2 determinants", Math. Comp. 82, 2013). So its sign is exact, and it
 * is zero only where the exact value is (products above the float range's 1e-38, where
 * underflow would lose the error term): what the paper's fallback to double precision gave,
 * without doubles, which is faster (docs/notes/performance-2026-11.md, 2026-11-27: the edge
 * function without doubles). Its products must not be contracted: FP_CONTRACT is off here. */
float edge_function(float ax, float ay, float bx, float by)
{
    float q = ay * bx;
    float q_error = fma(-ay, bx, q);
    return fma(ax, by, -q) + q_error;
}

/* The rows of the shear: transformed x = dot(row_x, v - o), etc. Rows hold zeros in the axes
 * they ignore, so each transformed coordinate is the paper's expression. */
void triangle_shear(float3 d, float3 *row_x, float3 *row_y, float3 *row_z)
{
    float3 a = fabs(d);
    int kz = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    float dz = kz == 0 ? d.x : kz == 1 ? d.y : d.z;
    if (dz < 0.0f) {                 /* keep the winding: swap x and y for a ray along -z */
        int k = kx; kx = ky; ky = k;
    }
    float dx = kx == 0 ? d.x : kx == 1 ? d.y : d.z;
    float dy = ky == 0 ? d.x : ky == 1 ? d.y : d.z;
    float3 ex = (float3)(kx == 0, kx == 1, kx == 2);
    float3 ey = (float3)(ky == 0, ky == 1, ky == 2);
    float3 ez = (float3)(kz == 0, kz == 1, kz == 2);
    *row_x = ex - (dx / dz) * ez;
    *row_y = ey - (dy / dz) * ez;
    *row_z = ez / dz;
}

/* dot(r, v) as a product and two fused multiply-adds, which FP_CONTRACT off would not form */
float dot_fma(float3 r, float3 v)
{
    return fma(r.x, v.x, fma(r.y, v.y, r.z * v.z));
}

CPU_INLINE float intersect_triangle(const global Triangle *tri, float3 o, float3 row_x,
                                    float3 row_y, float3 row_z, float t_max, float *b1, float *b2)
{
    float3 a = tri->v0.xyz - o, b = tri->v1.xyz - o, c = tri->v2.xyz - o;
    float ax = dot_fma(row_x, a), ay = dot_fma(row_y, a);
    float bx = dot_fma(row_x, b), by = dot_fma(row_y, b);
    float cx = dot_fma(row_x, c), cy = dot_fma(row_y, c);
    float u = edge_function(cx, cy, bx, by);    /* weight of v0 */
    float v = edge_function(ax, ay, cx, cy);    /* weight of v1 */
    float w = edge_function(bx, by, ax, ay);    /* weight of v2 */
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f))
        return INFINITY;
    float det = u + v + w;
    if (det == 0.0f)
        return INFINITY;
    float az = dot_fma(row_z, a), bz = dot_fma(row_z, b), cz = dot_fma(row_z, c);
    float t_scaled = u * az + v * bz + w * cz;
    /* t = t_scaled / det must lie in (0, t_max); compared before dividing, as in the paper */
    if (det < 0.0f ? (t_scaled >= 0.0f || t_scaled < t_max * det)
                   : (t_scaled <= 0.0f || t_scaled > t_max * det))
        return INFINITY;
    float inv = 1.0f / det;
    float t = t_scaled * inv;
    if (t <= 0.0f || t >= t_max)
        return INFINITY;
    *b1 = v * inv;
    *b2 = w * inv;
    return t;
}
#pragma OPENCL FP_CONTRACT ON

float3 triangle_normal(const global Triangle *tri)
{
    return normalize(cross(tri->v1.xyz - tri->v0.xyz, tri->v2.xyz - tri->v0.xyz));
}

float triangle_area(const global Triangle *tri)
{
    return 0.5f * length(cross(tri->v1.xyz - tri->v0.xyz, tri->v2.xyz - tri->v0.xyz));
}

/* The point of barycentric weights (b1, b2), its error bound (pbrt-v4 eq. 6.29: gamma(7) times
 * the sum of |b_i v_i|), the geometric normal, and the shading normal: the corners' normals
 * interpolated, turned to the geometric normal's side (which decides front and back).
 * A point on an edge may round to just beyond the plane of the neighbouring face, within its
 * error box; in a concave corner a ray leaving it would then start behind that face and pass
 * through. The point is moved towards the triangle's centroid by four times the length of its
 * error bound (never more than half the way): inside its own triangle and off the neighbour's
 * plane, by an amount that scales with the point's own rounding, not with the scene. The bound
 * grows to cover the move. */
void triangle_surface(const global Triangle *tri, const global float4 *normals, float b1, float b2,
                      float3 *p, float3 *error, float3 *ng, float3 *ns)
{
    float b0 = 1.0f - b1 - b2;
    float3 p0 = b0 * tri->v0.xyz, p1 = b1 * tri->v1.xyz, p2 = b2 * tri->v2.xyz;
    *error = gamma_bound(7) * (fabs(p0) + fabs(p1) + fabs(p2));
    *p = p0 + p1 + p2;
    float3 inward = (tri->v0.xyz + tri->v1.xyz + tri->v2.xyz) / 3.0f - *p;
    float len = length(inward);
    if (len > 0.0f) {
        float3 move = inward * fmin(4.0f * length(*error) / len, 0.5f);
        *p += move;
        *error += fabs(move);
    }
    *ng = triangle_normal(tri);
    int k = as_int(tri->v0.w);
    *ns = *ng;
    if (k >= 0) {
        float3 n = b0 * normals[k].xyz + b1 * normals[k + 1].xyz + b2 * normals[k + 2].xyz;
        float len = length(n);
        if (len > 0.0f)
            *ns = dot(n, *ng) < 0.0f ? -n / len : n / len;
    }
}

/* The texture coordinates at barycentric weights (b1, b2): the corners' interpolated, or (0, 0)
 * for a triangle without them. */
float2 triangle_uv(const global Triangle *tri, const global float2 *uvs, float b1, float b2)
{
    int k = as_int(tri->v1.w);
    if (k < 0)
        return (float2)(0.0f);
    return (1.0f - b1 - b2) * uvs[k] + b1 * uvs[k + 1] + b2 * uvs[k + 2];
}

/* A point uniform over the triangle's area: b1 = u2 sqrt(u1), b2 = 1 - sqrt(u1) (pbrt-v4
 * section 6.5.4 gives the same density); its density per area is 1 / area. Its barycentric
 * weights (b1, b2) go to *b. */
float3 sample_triangle_area(const global Triangle *tri, float u1, float u2, float2 *b)
{
    float s = sqrt(u1);
    float b1 = u2 * s, b2 = 1.0f - s;
    *b = (float2)(b1, b2);
    return (1.0f - b1 - b2) * tri->v0.xyz + b1 * tri->v1.xyz + b2 * tri->v2.xyz;
}

/* Density per solid angle, seen from x, of area sampling at point y of the triangle, whose
 * emitting side (its front, normal n, or either with `both_sides`) faces direction -w from x:
 * pdf_area * |x - y|^2 / |cos(theta_y)|; 0 from behind a one-sided emitter. */
float pdf_triangle_solid_angle(const global Triangle *tri, float3 x, float3 y, int both_sides)
{
    float3 w = y - x;
    float dist2 = dot(w, w);
    float cos_l = -dot(triangle_normal(tri), w) / sqrt(dist2);
    if (both_sides)
        cos_l = fabs(cos_l);
    return cos_l > 0.0f ? dist2 / (triangle_area(tri) * cos_l) : 0.0f;
}
