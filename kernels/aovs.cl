/* The denoiser's auxiliary images (Intel Open Image Denoise's "albedo" and "normal" inputs):
 * what each pixel sees at its first non-specular surface. As Cycles does, a path goes on
 * through mirrors and glass (delta BSDFs) to the next surface and takes that one's, with the
 * throughput of the delta bounces: a denoiser then keeps what a mirror shows sharp.
 *
 * The albedo is the BSDF's directional albedo rho(wo) = integral of f cos over wi, estimated by
 * the mean of ALBEDO_SAMPLES BSDF samples' weights f cos / pdf (each one's expectation is rho,
 * so the running mean converges to it; for a diffuse surface every sample is exactly its
 * reflectance). Sampling a BSDF traces no ray, so several cost little, and a material whose
 * lobes differ in colour (the report's Phong) would otherwise give the denoiser a speckled
 * albedo at low sample counts, which it keeps as if it were texture. An emitter adds its
 * radiance, a path that escapes takes the environment's: lights and the sky are then edges the
 * denoiser keeps. The host clamps the mean to [0, 1], the range the denoiser expects. The
 * normal is the shading normal, facing the ray; an escaping path has none (0). The depth is
 * the camera ray's distance to the first surface it hits, mirrors or not (Mitsuba 3's `aov`
 * integrator's "depth"); 0 where it escapes.
 *
 * A separate kernel, not a branch of the integrator: the path tracer pays nothing when no one
 * denoises, and the first hit is the beauty sample's own (same sample index, same jitter). */

/* delta bounces followed before giving up (a hall of mirrors): the pixel then keeps black */
#define AOV_MAX_DELTA 8
#define ALBEDO_SAMPLES 4

/* The mean weight of ALBEDO_SAMPLES samples of m's BSDF seen from wo; `first` is one already
 * drawn. */
float3 estimate_albedo(MaterialRef m, float3 wo, const BSDFSample *first, Rng *rng)
{
    float3 sum = first->weight;
    for (int i = 1; i < ALBEDO_SAMPLES; ++i) {
        BSDFSample bs;
        bs.eta = 1.0f;
        if (sample_bsdf(m, wo, next_uniform4(rng).xyz, &bs))
            sum += bs.weight;
    }
    return sum / ALBEDO_SAMPLES;
}

void trace_aovs(const SceneData *sc, const RenderParams *p, float3 o, float3 d, Rng *rng,
                float3 *albedo, float3 *normal, float *depth)
{
    float3 throughput = (float3)(1.0f);
    PrimId self = NO_PRIM;
    for (int bounce = 0; bounce <= AOV_MAX_DELTA; ++bounce) {
        Hit hit = intersect_scene(sc, o, d, INFINITY, self);
        if (bounce == 0)
            *depth = hit.prim < 0 ? 0.0f : hit.t;
        if (hit.prim < 0) {
            *albedo = throughput * lookup_environment(sc->env, p, d);
            return;
        }
        Surface s = surface_at(sc, &hit, o, d);
        int flags = sc->materials[sc->prim_material[hit.prim]].flags;
#ifdef NULL_SURFACES
        if (flags & MATERIAL_NULL) {        /* no surface (the media themselves are not guides) */
            o = offset_ray_origin(s.p, s.offset, s.ng, d);
            self = HIT_ID(hit);
            continue;
        }
#endif
        int front = dot(s.ng, d) < 0.0f;
        if (!front && (flags & MATERIAL_TWOSIDED))
            turn_round(&s);
        MATERIAL_AT(m, sc, s, d);
        float3 wo = to_shading(&s, -d);
        BSDFSample bs;
        bs.eta = 1.0f;
        int sampled = (front || (m->flags & (MATERIAL_TWOSIDED | MATERIAL_TRANSMISSIVE)))
                      && sample_bsdf(m, wo, next_uniform4(rng).xyz, &bs);
        if (!(m->flags & MATERIAL_DELTA) || !sampled) {
            float3 rho = sampled ? estimate_albedo(m, wo, &bs, rng) : (float3)(0.0f);
            float3 le = front || (flags & MATERIAL_EMITS_BACK) ? m->emission.xyz : (float3)(0.0f);
            *albedo = throughput * (rho + le);
            *normal = dot(s.ns, d) > 0.0f ? -s.ns : s.ns;
            return;
        }
        float3 wi = from_shading(&s, bs.wi);
        throughput *= bs.weight;
        o = offset_ray_origin(s.p, s.offset, s.ng, wi);
        d = wi;
        self = HIT_ID(hit);
    }
}

/* Adds p.sample_count samples of albedo (rgb) and normal (xyz) to each pixel of rows
 * [row_start, row_end), for the same sample indices as the render kernels; albedo_sum's w
 * counts them, normal_sum's w sums the depth. */
#ifdef ENTRY_AUX
kernel void render_aovs(SCENE_KERNEL_ARGS, const RenderParams p, global float4 *albedo_sum,
                        global float4 *normal_sum)
{
    SceneData sc = SCENE_DATA(p.num_spheres, p.layout);
    int x = get_global_id(0), y = p.row_start + get_global_id(1);
    if (x >= p.width || y >= p.row_end)
        return;
    float3 albedo_acc = (float3)(0.0f), normal_acc = (float3)(0.0f);
    float depth_acc = 0.0f;
    for (uint i = 0; i < p.sample_count; ++i) {
        Rng rng = make_rng(x, y, p.sample_start + i, p.seed);
        CameraRay ray = sample_camera_ray(&p, x, y, &rng);
        float3 albedo = (float3)(0.0f), normal = (float3)(0.0f);
        float depth = 0.0f;
        trace_aovs(&sc, &p, ray.o, ray.d, &rng, &albedo, &normal, &depth);
        if (all(isfinite(albedo)))
            albedo_acc += albedo;
        normal_acc += normal;
        depth_acc += depth;
    }
    int k = y * p.width + x;
    albedo_sum[k] += (float4)(albedo_acc, (float)p.sample_count);
    normal_sum[k] += (float4)(normal_acc, depth_acc);
}
#endif
