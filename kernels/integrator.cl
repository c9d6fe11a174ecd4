/* The path tracer: the report's Algorithm 1 (GetRadianceLi), one ray per bounce, extended by
 * next-event estimation. A path's vertex count is its depth; the camera ray's hit is depth 1.
 *
 * The kernel `render` is the report's estimator: light arrives only when a path happens to hit
 * an emitter or escape to the environment. In `render_nee` every vertex also samples a light (an
 * emissive sphere, or the environment) and traces a shadow ray; both ways of reaching a light
 * are kept and weighted by multiple importance sampling (power heuristic), so the estimate is
 * unbiased and the two settings converge to the same image. */

/* The safety bound on path length when Russian roulette alone ends paths (max_depth 0): only a
 * closed scene of albedo 1 could reach it. */
#define UNLIMITED_DEPTH 1024

typedef struct {
    const global BVHNode *nodes;
    const global Sphere *spheres;
    const global Material *materials;
    const global float4 *env;
    const global Light *lights;
    const global float *light_pick;       /* per sphere: probability of choosing it as a light */
    const global float *env_marginal;
    const global float *env_conditional;
} SceneData;

/* Density with which next-event estimation at a vertex (p, n) samples direction d towards the
 * environment: cosine-weighted for a constant colour, the map's distribution otherwise. */
float pdf_environment(const SceneData *sc, const RenderParams *p, float3 n, float3 d)
{
    if (p->env_width == 1 && p->env_height == 1)
        return pdf_cosine_hemisphere(dot(n, d));
    return pdf_environment_map(sc->env_marginal, sc->env_conditional, p, d);
}

/* One light sample at vertex (x, n) with outgoing direction wo: its contribution
 * f cos Le / pdf, weighted against BSDF sampling. `self` is the sphere x lies on. */
float3 sample_direct_light(const SceneData *sc, const RenderParams *p, const Material *m,
                           float3 x, float3 n, float3 wo, int self, float4 u, int *rays)
{
    float3 wi, le;
    float pdf_light;
    int target;                                    /* the sphere the shadow ray must meet first */
    if (u.x < p->env_pick) {
        wi = (p->env_width == 1 && p->env_height == 1)
                 ? to_world(sample_cosine_hemisphere(u.y, u.z), n)
                 : sample_environment_map(sc->env_marginal, sc->env_conditional, p, u.y, u.z);
        pdf_light = p->env_pick * pdf_environment(sc, p, n, wi);
        target = -1;
    } else {
        int k = pick_light(sc->lights, p->num_lights, (u.x - p->env_pick) / (1.0f - p->env_pick));
        target = sc->lights[k].sphere;
        if (target == self)                        /* a convex sphere cannot light itself */
            return (float3)(0.0f);
        Sphere s = sc->spheres[target];
        wi = sample_sphere_cone(s, x, u.y, u.z);
        pdf_light = (1.0f - p->env_pick) * sc->lights[k].pick * pdf_sphere_cone(s, x);
    }
    float cos_i = dot(n, wi);
    if (pdf_light <= 0.0f || cos_i <= 0.0f)
        return (float3)(0.0f);
    float3 f = eval_phong(m, n, wo, wi);
    if (all(f == 0.0f))
        return (float3)(0.0f);
    ++*rays;
    Hit h = intersect_scene(sc->nodes, sc->spheres, x, wi, INFINITY, self);
    if (h.sphere != target)
        return (float3)(0.0f);                     /* occluded */
    le = target < 0 ? lookup_environment(sc->env, p, wi) : sc->materials[target].emission.xyz;
    float w = mis_weight(pdf_light, pdf_continue(m, n, wo, wi, p->russian_roulette));
    return f * cos_i * le * (w / pdf_light);
}

/* Returns the radiance arriving at o from direction -d; adds the rays it traced to *rays.
 * `nee` is a constant in each kernel below, so the compiler builds one lean path tracer
 * without the light sampling code and one with it. */
float3 trace_path(const SceneData *sc, const RenderParams *p, float3 o, float3 d, Rng *rng,
                  int *rays, const int nee)
{
    float3 radiance = (float3)(0.0f);
    float3 throughput = (float3)(1.0f);
    int max_depth = p->max_depth > 0 ? p->max_depth : UNLIMITED_DEPTH;
    int skip = -1;
    /* where the last bounce left from, and how likely BSDF sampling was to choose d there
     * (0 for the camera ray: nothing else could have found what it hits) */
    float3 prev_x = o, prev_n = (float3)(0.0f);
    float pdf_bsdf = 0.0f;
    for (int depth = 1;; ++depth) {
        ++*rays;
        Hit hit = intersect_scene(sc->nodes, sc->spheres, o, d, INFINITY, skip);
        if (hit.sphere < 0) {
            float w = 1.0f;
            if (nee && pdf_bsdf > 0.0f && p->env_pick > 0.0f)
                w = mis_weight(pdf_bsdf, p->env_pick * pdf_environment(sc, p, prev_n, d));
            return radiance + throughput * lookup_environment(sc->env, p, d) * w;
        }
        Sphere s = sc->spheres[hit.sphere];
        /* Project the hit back onto the sphere, removing the error of o + t d. */
        float3 n = normalize(o + hit.t * d - s.xyz);
        /* Spheres are solid and one-sided, as Mitsuba 3's BSDFs and area lights: their inside
         * neither reflects nor emits. */
        if (dot(n, d) >= 0.0f)
            return radiance;
        Material m = sc->materials[hit.sphere];
        if (any(m.emission.xyz > 0.0f)) {
            float w = 1.0f;
            if (nee && pdf_bsdf > 0.0f)
                w = mis_weight(pdf_bsdf, (1.0f - p->env_pick) * sc->light_pick[hit.sphere]
                                             * pdf_sphere_cone(s, prev_x));
            radiance += throughput * m.emission.xyz * w;
        }
        if (depth >= max_depth)
            return radiance;
        float3 x = s.xyz + s.w * n;
        if (nee)
            radiance += throughput * sample_direct_light(sc, p, &m, x, n, -d, hit.sphere,
                                                         next_uniform4(rng), rays);
        float3 wi, weight;
        if (!sample_phong(&m, n, -d, next_uniform4(rng), p->russian_roulette, &wi, &weight))
            return radiance;
        pdf_bsdf = pdf_continue(&m, n, -d, wi, p->russian_roulette);
        throughput *= weight;
        prev_x = x;
        prev_n = n;
        o = x;
        d = wi;
        skip = hit.sphere;
    }
}

/* One work-item per pixel adds p.sample_count samples to the running sums of radiance (rgb; w
 * counts samples) and of its square (rgb, for the per-pixel variance; w counts rays traced). */
void render_pixel(const SceneData *sc, const RenderParams *p, global float4 *sum,
                  global float4 *sum_sq, const int nee)
{
    int x = get_global_id(0), y = get_global_id(1);
    if (x >= p->width || y >= p->height)
        return;
    float3 acc = (float3)(0.0f), acc_sq = (float3)(0.0f);
    int rays = 0;
    for (uint i = 0; i < p->sample_count; ++i) {
        Rng rng = make_rng(x, y, p->sample_start + i, p->seed);
        float4 jitter = next_uniform4(&rng);
        float3 d = camera_direction(p, x + jitter.x, y + jitter.y);
        float3 l = trace_path(sc, p, p->eye.xyz, d, &rng, &rays, nee);
        acc += l;
        acc_sq += l * l;
    }
    int k = y * p->width + x;
    sum[k] += (float4)(acc, (float)p->sample_count);
    sum_sq[k] += (float4)(acc_sq, (float)rays);
}

#define RENDER_KERNEL(name, nee)                                                                 \
    kernel void name(const global BVHNode *nodes, const global Sphere *spheres,                 \
                     const global Material *materials, const global float4 *env,                \
                     const global Light *lights, const global float *light_pick,                \
                     const global float *env_marginal, const global float *env_conditional,     \
                     const RenderParams p, global float4 *sum, global float4 *sum_sq)           \
    {                                                                                            \
        SceneData sc = {nodes, spheres, materials, env, lights, light_pick, env_marginal,        \
                        env_conditional};                                                        \
        render_pixel(&sc, &p, sum, sum_sq, nee);                                                 \
    }

/* render: the report's estimator; render_nee: with next-event estimation */
RENDER_KERNEL(render, 0)
RENDER_KERNEL(render_nee, 1)
