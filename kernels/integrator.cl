/* The path tracer: the report's Algorithm 1 (GetRadianceLi), one ray per bounce, implicit
 * lights only. A path's vertex count is its depth; the camera ray's hit is depth 1. */

/* The safety bound on path length when Russian roulette alone ends paths (max_depth 0): only a
 * closed scene of albedo 1 could reach it. */
#define UNLIMITED_DEPTH 1024

/* Returns the radiance arriving at o from direction -d; adds the rays it traced to *rays. */
float3 trace_path(const global BVHNode *nodes, const global Sphere *spheres,
                  const global Material *materials, const global float4 *env,
                  const RenderParams *p, float3 o, float3 d, Rng *rng, int *rays)
{
    float3 radiance = (float3)(0.0f);
    float3 throughput = (float3)(1.0f);
    int max_depth = p->max_depth > 0 ? p->max_depth : UNLIMITED_DEPTH;
    int skip = -1;
    for (int depth = 1;; ++depth) {
        ++*rays;
        Hit hit = intersect_scene(nodes, spheres, o, d, INFINITY, skip);
        if (hit.sphere < 0)
            return radiance + throughput * lookup_environment(env, p, d);
        Sphere s = spheres[hit.sphere];
        /* Project the hit back onto the sphere, removing the error of o + t d. */
        float3 n = normalize(o + hit.t * d - s.xyz);
        /* Spheres are solid and one-sided, as Mitsuba 3's BSDFs and area lights: their inside
         * neither reflects nor emits. */
        if (dot(n, d) >= 0.0f)
            return radiance;
        Material m = materials[hit.sphere];
        radiance += throughput * m.emission.xyz;
        if (depth >= max_depth)
            return radiance;
        float3 wi, weight;
        if (!sample_phong(&m, n, -d, next_uniform4(rng), p->russian_roulette, &wi, &weight))
            return radiance;
        throughput *= weight;
        o = s.xyz + s.w * n;
        d = wi;
        skip = hit.sphere;
    }
}

/* One work-item per pixel adds p.sample_count samples to the running sums of radiance (rgb; w
 * counts samples) and of its square (rgb, for the per-pixel variance; w counts rays traced). */
kernel void render(const global BVHNode *nodes, const global Sphere *spheres,
                   const global Material *materials, const global float4 *env,
                   const RenderParams p, global float4 *sum, global float4 *sum_sq)
{
    int x = get_global_id(0), y = get_global_id(1);
    if (x >= p.width || y >= p.height)
        return;
    float3 acc = (float3)(0.0f), acc_sq = (float3)(0.0f);
    int rays = 0;
    for (uint i = 0; i < p.sample_count; ++i) {
        Rng rng = make_rng(x, y, p.sample_start + i, p.seed);
        float4 jitter = next_uniform4(&rng);
        float3 d = camera_direction(&p, x + jitter.x, y + jitter.y);
        float3 l = trace_path(nodes, spheres, materials, env, &p, p.eye.xyz, d, &rng, &rays);
        acc += l;
        acc_sq += l * l;
    }
    int k = y * p.width + x;
    sum[k] += (float4)(acc, (float)p.sample_count);
    sum_sq[k] += (float4)(acc_sq, (float)rays);
}
