/* Points, vectors, normals and error bounds moved by a 3x4 affine transform given as its rows:
 * an instance's (kernels/bvh.cl) and an analytic shape's (kernels/shapes/analytic.cl). */

float3 transform_point(const global float4 *rows, float3 p)
{
    return (float3)(dot(rows[0].xyz, p), dot(rows[1].xyz, p), dot(rows[2].xyz, p))
           + (float3)(rows[0].w, rows[1].w, rows[2].w);
}

float3 transform_vector(const global float4 *rows, float3 v)
{
    return (float3)(dot(rows[0].xyz, v), dot(rows[1].xyz, v), dot(rows[2].xyz, v));
}

/* p's error bound after p (error `error` before) was moved by the transform `rows` (pbrt-v4's
 * Transform of a Point3fi: the rounding of the product added). */
float3 transform_error(const global float4 *rows, float3 p, float3 error)
{
    float3 m0 = fabs(rows[0].xyz), m1 = fabs(rows[1].xyz), m2 = fabs(rows[2].xyz);
    float3 moved = (float3)(dot(m0, error), dot(m1, error), dot(m2, error));
    float3 size = (float3)(dot(m0, fabs(p)), dot(m1, fabs(p)), dot(m2, fabs(p)))
                  + fabs((float3)(rows[0].w, rows[1].w, rows[2].w));
    return (1.0f + gamma_bound(3)) * moved + gamma_bound(3) * size;
}

/* A unit normal moved by the inverse transpose of the transform whose inverse's rows are
 * `to_object`: the transpose of those rows. */
float3 transform_normal(const global float4 *to_object, float3 n)
{
    return unit(n.x * to_object[0].xyz + n.y * to_object[1].xyz + n.z * to_object[2].xyz);
}
