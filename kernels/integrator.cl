/* The path tracer: the report's Algorithm 1 (GetRadianceLi), one ray per bounce, extended by
 * next-event estimation. A path's vertex count is its depth; the camera ray's hit is depth 1.
 *
 * The kernel `render` is the report's estimator: light arrives only when a path happens to hit
 * an emitter or escape to the environment. In `render_nee` every vertex with a non-delta BSDF
 * also samples a light and traces a shadow ray; both ways of reaching a light are kept and
 * weighted by multiple importance sampling (power heuristic), so the estimate is unbiased and
 * the two settings converge to the same image. Emitters reached through a delta bounce carry
 * no MIS weight, since light sampling could not have found them.
 *
 * A direction's side is the shading frame's, as in pbrt-v4 and Mitsuba 3: where the shading
 * and geometric normals put it on different sides it is followed (its ray leaves on the
 * geometric side it points to), not dropped: pbrt-v3's guard against light leaks, which dropped
 * it, darkened smooth-shaded meshes against Mitsuba 3's renders (tests/scenes/glass-mesh.xml,
 * open-sheet.xml; docs/mitsuba.md). Mitsuba's normal and bump maps alone drop a direction that
 * the perturbed and unperturbed normals put on different sides, as Mitsuba 3 does
 * (PERTURBED_SIDES_AGREE). */

/* The safety bound on path length when Russian roulette alone ends paths (max_depth 0): only a
 * closed scene of albedo 1 could reach it. */
#define UNLIMITED_DEPTH 1024

/* How paths end: the build option RUSSIAN_ROULETTE (app/device/features.py) picks one rule per
 * program, so that the others cost no registers. */
#define RR_OFF 0
#define RR_ALBEDO 1        /* the report's: at every vertex, go on with the material's albedo
                              (Material.continuation), folded into the lobe choice */
#define RR_THROUGHPUT 2    /* from rr_depth on, go on with probability min(max throughput, 0.95)
                              (Mitsuba 3's; pbrt-v4 has no cap) */
#ifdef GENERIC
#define RUSSIAN_ROULETTE (p->rr_rule)   /* a GENERIC program's choice at run time */
#endif

/* The fraction of light sample ls's radiance that reaches o, a ray leaving surface `self` (or
 * NO_PRIM) in `medium` (-1: none): 1 or 0 by whether a shadow ray from o towards the point on the
 * light meets nothing before it (stopping just short, by pbrt-v4's ShadowEpsilon: pbrt's
 * SpawnRayTo; a light at infinity is seen if the ray meets nothing at all), or in a scene with
 * media the transmittance along it (kernels/volume.cl). */
float3 light_visibility(const SceneData *sc, float3 o, const LightSample *ls, PrimId self, int medium,
                        int *rays)
{
    float3 dir = ls->wi;
    float t_max = INFINITY;
    if (!(ls->flags & LIGHT_AT_INFINITY)) {
        t_max = norm(ls->y - o);
        dir = (ls->y - o) / t_max;
        t_max *= 1.0f - SHADOW_EPSILON;
    }
    ++*rays;
#ifdef MEDIA
    return transmittance_along(sc, o, dir, t_max, self, medium, rays);
#else
    return occluded(sc, o, dir, t_max, self) ? (float3)(0.0f) : (float3)(1.0f);
#endif
}

/* The weight of light emitted at point y of primitive `prim` towards the previous vertex x
 * (normal n; 0 after a scattering in a medium): the power heuristic against the light sampling
 * that could have found y from x, where the path chose its direction with density pdf_prev (0:
 * a delta lobe or the camera ray, which no light sample could have found). */
float emission_weight(const SceneData *sc, int prim, const int nee, float pdf_prev, float3 x, float3 n, float3 y)
{
    return nee && pdf_prev > 0.0f ? mis_weight(pdf_prev, pdf_light(sc, prim, x, n, y)) : 1.0f;
}

/* One light sample at surface s, whose BSDF m sees outgoing direction wo (local frame of the
 * shading normal): its contribution f cos Le / pdf, weighted against BSDF sampling, whose
 * density of continuing is `go_on` times the BSDF's pdf (a delta light, which no path can find,
 * keeps its whole weight). Everything but visibility is computed before the shadow ray, so
 * that only the contribution stays live while it is traced; the shadow ray leaves s into the
 * medium on the light's side (`medium` where s bounds none). */
float3 sample_direct_light(const SceneData *sc, const RenderParams *p, MaterialRef m,
                           const Surface *s, float3 wo, float go_on, int medium, uint4 r, Rng *rng,
                           int *rays)
{
    LightSample ls = sample_light(sc, p, s->p, s->ns, r, rng);
    LOG_LIGHT_SAMPLED(sc, ls);
    float3 wi = to_shading(s, ls.wi);
    if (ls.pdf <= 0.0f || !PERTURBED_SIDES_AGREE(s, ls.wi, wi.z))
        return (float3)(0.0f);
    float pdf;
    float3 f = eval_pdf_bsdf(m, wo, wi, &pdf);
    if (all(f == 0.0f))
        return (float3)(0.0f);
#ifdef NORMAL_MAPS
    f *= shadow_terminator(s, ls.wi);
#endif
    float w = (ls.flags & LIGHT_DELTA) ? 1.0f : mis_weight(ls.pdf, go_on * pdf);
    float3 contribution = f * fabs(wi.z) * ls.le * (w / ls.pdf);
    float3 o = offset_ray_origin(s->p, s->offset, s->ng, ls.wi);
#ifdef MEDIA
    medium = medium_after(sc, s, ls.wi, medium);
#endif
    return contribution * light_visibility(sc, o, &ls, SURFACE_ID(*s), medium, rays);
}

#ifdef MEDIA
/* One light sample at point x inside a medium whose phase function has mean cosine g, the path
 * arriving along -wo: the phase function's value times the light's radiance and the
 * transmittance towards it, over its density, weighted against phase-function sampling (power
 * heuristic; a delta light keeps its whole weight). */
float3 sample_direct_light_in_medium(const SceneData *sc, const RenderParams *p, float3 x, float3 wo,
                                     float g, int medium, uint4 r, Rng *rng, int *rays)
{
    /* no normal: the light tree weighs no cosine, a constant environment is sampled uniformly */
    LightSample ls = sample_light(sc, p, x, (float3)(0.0f), r, rng);
    LOG_LIGHT_SAMPLED(sc, ls);
    if (ls.pdf <= 0.0f)
        return (float3)(0.0f);
    float phase = eval_hg(g, wo, ls.wi);
    float w = (ls.flags & LIGHT_DELTA) ? 1.0f : mis_weight(ls.pdf, phase);
    float3 contribution = ls.le * (phase * w / ls.pdf);
    return contribution * light_visibility(sc, x, &ls, NO_PRIM, medium, rays);
}
#endif

/* Russian roulette on throughput (RR_THROUGHPUT): go on with probability min(max throughput
 * eta^2, 0.95), from uniform u, dividing the throughput by it; returns 0 when the path ends. */
int survives_roulette(float3 *throughput, float eta_scale, float u)
{
    float q = fmin(fmax(fmax(throughput->x, throughput->y), throughput->z) * eta_scale * eta_scale, 0.95f);
    if (u >= q)
        return 0;
    *throughput /= q;
    return 1;
}

/* A path leaving the camera along o + t d (with MEDIA, it draws its hero channel from rng). */
PathRecord start_path(const RenderParams *p, float3 o, float3 d, Rng *rng)
{
    PathRecord path;
    path.o = (float4)(o, 1.0f);                                  /* eta_scale */
    path.d = (float4)(d, 0.0f);                                  /* pdf_prev */
    path.throughput = (float4)((float3)(1.0f), as_float(1));     /* depth */
    path.radiance = (float4)((float3)(0.0f), as_float(p->camera_medium));
    path.prev_x = (float4)(o, as_float(-1));                     /* no surface left */
    path.prev_n = (float4)((float3)(0.0f), as_float(-1));
    path.ratios = (float4)((float3)(1.0f), 0.0f);
#ifdef MEDIA
    path.ratios.w = as_float(min((int)(next_uniform4(rng).x * 3.0f), 2));
#endif
    path.rng = (uint4)(rng->key.xyz, rng->dim);
    return path;
}

/* Returns the radiance arriving at a path's origin along its ray, from the state `start` (a
 * path from the camera, start_path, or one taken from the continuation queue); adds the rays it
 * traced to *rays. `nee` is a constant in each kernel below, so the compiler builds one lean
 * path tracer without the light sampling code and one with it. In a scene with media (MEDIA),
 * each segment of the path first samples a free flight in the medium it crosses
 * (kernels/media/): the path scatters inside the medium by the phase function
 * (kernels/phase.cl), with light sampling as at a surface, or reaches the surface, whose
 * crossing may change the medium (kernels/volume.cl).
 *
 * With PATH_QUEUE (the render setting path_queue, app/device/features.py), a path about to trace its
 * ray to vertex queue.depth is stored in `queue` instead, where it has room (*queued set, the
 * radiance returned is not the path's), and continue_paths traces it on. A GPU runs a warp's 32
 * paths in step until the longest ends: where a few paths go on bouncing among meshes, the
 * others' lanes idle for every vertex they add (Laine, Karras and Aila 2013, "Megakernels
 * Considered Harmful"); gathered into a queue, the paths that go on fill whole warps, at the
 * cost of storing and loading them (docs/notes/performance-2026-11.md, 2026-11-26, says where that pays).
 * With PATH_SORT continue_paths takes the queue's paths in the order of their rays' keys, so that
 * a warp's rays start near one another and run alike through the tree (kernels/path_sort.cl).
 *
 * On CPUs it is inlined (CPU_INLINE), so that the start state stays in registers: PoCL left the call out of
 * line and passed the state through memory. NVIDIA's compiler keeps it out of line too, and GPUs
 * keep that form, the one measured (docs/notes/performance-2026-11.md, 2026-11-26: the continuation queue). */
CPU_INLINE float3 trace_path(const SceneData *sc, const RenderParams *p, const PathRecord *start,
                             Rng *rng, int *rays, const int nee, PathQueue queue, int *queued)
{
    float3 o = start->o.xyz, d = start->d.xyz;
    float3 radiance = start->radiance.xyz;
    float3 throughput = start->throughput.xyz;
    /* the product of the relative IORs of the refractions so far: throughput eta^2 is the
     * throughput without the radiance scaling of dense media, which Russian roulette reads */
    float eta_scale = start->o.w;
    int max_depth = p->max_depth > 0 ? p->max_depth : UNLIMITED_DEPTH;
    /* where the last bounce left from, and the density with which BSDF sampling chose d there
     * (0 for the camera ray and delta bounces: no light sample could have found what it hits);
     * prev_n is 0 after a scattering in a medium */
    float3 prev_x = start->prev_x.xyz, prev_n = start->prev_n.xyz;
    float pdf_prev = start->d.w;
    /* the surface the ray leaves */
    PrimId self = PRIM_ID_OF_PAIR(((int2)(as_int(start->prev_x.w), as_int(start->prev_n.w))));
    /* the medium the ray crosses, or -1 (a program without media never reads it) */
    int medium = as_int(start->radiance.w);
#ifdef MEDIA
    /* the channel whose free flights the path samples, and each channel's path density over
       the hero's (kernels/media/homogeneous.cl), scaled to a mean of 1 */
    int hero = as_int(start->ratios.w);
    float3 ratios = start->ratios.xyz;
#endif
    for (int depth = as_int(start->throughput.w);; ++depth) {
#ifdef PATH_QUEUE
        if (depth == queue.depth && queue.capacity > 0) {
            int2 left = PRIM_ID_PAIR(self);
            PathRecord r;
            r.o = (float4)(o, eta_scale);
            r.d = (float4)(d, pdf_prev);
            r.throughput = (float4)(throughput, as_float(depth));
            r.radiance = (float4)(radiance, as_float(medium));
            r.prev_x = (float4)(prev_x, as_float(left.x));
            r.prev_n = (float4)(prev_n, as_float(left.y));
#ifdef MEDIA
            r.ratios = (float4)(ratios, as_float(hero));
#endif
            r.rng = (uint4)(rng->key.xyz, rng->dim);
            if (enqueue_path(queue, &r, QUEUE_KEY(queue, d, self))) {
                *queued = 1;
                return radiance;
            }
        }
#endif
        LOG_ITERATION(sc);
        ++*rays;
        Hit hit = intersect_scene(sc, o, d, INFINITY, self);
#ifdef MEDIA
        if (medium >= 0) {
            const global Medium *med = &sc->media[medium];
            float4 u = next_uniform4(rng);
            FreeFlight flight = sample_free_flight(med, hit.t, hero, u.x);
            /* throughput stays the path's f over its channel-averaged density (ratios keep a
               mean of 1), so that every estimate below is spectral MIS's */
            float3 ratios_next = ratios * flight.ratio;
            float mean_ratio = dot(ratios_next, (float3)(1.0f / 3.0f));
            throughput *= flight.weight / mean_ratio;
            ratios = ratios_next / mean_ratio;
            if (flight.scattered) {
                if (depth >= max_depth || all(throughput == 0.0f))
                    return radiance;
                LOG_SHADED(sc, SHADING_MEDIUM);
                float3 x = o + flight.t * d, wo = -d;
                float g = med->sigma_s.w;
                if (nee && p->num_lights > 0)
                    radiance += throughput * sample_direct_light_in_medium(sc, p, x, wo, g, medium,
                                                                           next_bits4(rng), rng, rays);
                /* the phase function is sampled exactly: its weight is 1 */
                d = sample_hg(g, wo, u.zw, &pdf_prev);
                if (RUSSIAN_ROULETTE != RR_OFF && depth >= p->rr_depth
                    && !survives_roulette(&throughput, eta_scale, next_uniform4(rng).x))
                    return radiance;
                prev_x = o = x;
                prev_n = (float3)(0.0f);
                self = NO_PRIM;
                continue;
            }
        }
#endif
        if (hit.prim < 0) {
            LOG_SHADED(sc, SHADING_ESCAPED);
            float w = 1.0f;
            if (nee && pdf_prev > 0.0f && p->env_pick > 0.0f)
                w = mis_weight(pdf_prev, p->env_pick * pdf_environment(sc, p, prev_n, d));
            return radiance + throughput * lookup_environment(sc->env, p, d) * w;
        }
        Surface s = surface_at(sc, &hit, o, d);
        int flags = sc->materials[sc->prim_material[hit.prim]].flags;
#ifdef NULL_SURFACES
        if (flags & MATERIAL_NULL) {
            /* no vertex: the ray goes on through, into the medium beyond */
            LOG_SHADED(sc, SHADING_NULL);
            medium = medium_after(sc, &s, d, medium);
            o = offset_ray_origin(s.p, s.offset, s.ng, d);
            self = HIT_ID(hit);
            --depth;
            continue;
        }
#endif
        int front = dot(s.ng, d) < 0.0f;
        /* One-sided, as Mitsuba 3's BSDFs and area lights: a back face scatters nothing. A
         * two-sided material turns its frame round; a transmissive one (glass) keeps it and its
         * BSDF sees wo below the surface. Light leaves the front, or both sides of one surface
         * (pbrt-v4's twoSided DiffuseAreaLight::L tests no side). */
        int emits = front || (flags & MATERIAL_EMITS_BACK);
        int scatters = front || (flags & (MATERIAL_TWOSIDED | MATERIAL_TRANSMISSIVE));
        if (!front && (flags & MATERIAL_TWOSIDED))
            turn_round(&s);
        if (depth >= max_depth || !scatters) {
            /* the last vertex: only the light it emits counts, so its material is not shaded
               (pbrt-v4's PathIntegrator also ends a path at maxDepth before getting its BSDF) */
            LOG_SHADED(sc, SHADING_LAST_VERTEX);
            float3 le = emits ? EMISSION_AT(sc, s, d) : (float3)(0.0f);
            if (any(le > 0.0f))
                radiance += throughput * le * emission_weight(sc, hit.prim, nee, pdf_prev, prev_x, prev_n, s.p);
            return radiance;
        }
        MATERIAL_AT(m, sc, s, d);
        LOG_BSDF(sc, hit.prim, m->type);
        if (emits && any(m->emission.xyz > 0.0f))
            radiance += throughput * m->emission.xyz
                        * emission_weight(sc, hit.prim, nee, pdf_prev, prev_x, prev_n, s.p);
        float3 wo = to_shading(&s, -d);
        float go_on = RUSSIAN_ROULETTE == RR_ALBEDO ? m->continuation : 1.0f;
        if (nee && p->num_lights > 0 && !(m->flags & MATERIAL_DELTA))
            radiance += throughput * sample_direct_light(sc, p, m, &s, wo, go_on,
                                                         medium, next_bits4(rng), rng, rays);
        float4 u = next_uniform4(rng);
        if (RUSSIAN_ROULETTE == RR_ALBEDO) {
            if (u.x >= go_on)
                return radiance;
            u.x /= go_on;                    /* reused for the lobe choice, as in the report */
        }
        BSDFSample bs;
        bs.eta = 1.0f;
        if (!sample_bsdf(m, wo, u.xyz, &bs))
            return radiance;
        float3 wi = from_shading(&s, bs.wi);
        if (!PERTURBED_SIDES_AGREE(&s, wi, bs.wi.z))
            return radiance;
        throughput *= bs.weight / go_on;
#ifdef NORMAL_MAPS
        throughput *= shadow_terminator(&s, wi);
#endif
        eta_scale *= bs.eta;
        if (RUSSIAN_ROULETTE == RR_THROUGHPUT && depth >= p->rr_depth
            && !survives_roulette(&throughput, eta_scale, u.w))
            return radiance;
        pdf_prev = (bs.lobe & LOBE_DELTA) ? 0.0f : go_on * bs.pdf;
        prev_x = s.p;
        prev_n = s.ns;
        o = offset_ray_origin(s.p, s.offset, s.ng, wi);
        d = wi;
        self = HIT_ID(hit);
#ifdef MEDIA
        medium = medium_after(sc, &s, wi, medium);
#endif
    }
}

/* Compensated summation (Kahan, "Further remarks on reducing truncation errors", CACM 8(1),
 * 1965): *s + x, the low-order part that rounding loses kept in *c (the sum is *s - *c), so that
 * a pixel's running sums stay accurate to a few ulps after millions of samples, where a plain
 * float32 sum of N samples rounds each new one by up to 2^-24 N of the total (a viewer left
 * running for hours stopped converging). No reassociation is allowed (no
 * -cl-fast-relaxed-math), so the compiler keeps (t - s) - y. Within a launch the samples are
 * summed plainly, in registers: a launch adds at most MAX_LAUNCH_SAMPLES (app/rendering/renderer.py). */
void add_compensated(float4 *s, float4 *c, float4 x)
{
    float4 y = x - *c;
    float4 t = *s + y;
    *c = (t - *s) - y;
    *s = t;
}

/* Adds a sample's radiance l to a pixel's sums of the launch, if it is finite (kept counts
 * those added; render_pixel documents what becomes of the others). */
void add_sample(float3 l, float3 *acc, float3 *acc_sq, int *kept)
{
    if (all(isfinite(l))) {
        *acc += l;
        *acc_sq += l * l;
        ++*kept;
    }
}

/* Adds a launch's samples of pixel k to its running sums of radiance (rgb; w counts the samples
 * kept) and of its square (rgb, for the per-pixel variance; w counts rays traced), compensated
 * (sum_c and sum_sq_c hold what rounding lost). */
void add_to_pixel(global float4 *sum, global float4 *sum_sq, global float4 *sum_c,
                  global float4 *sum_sq_c, int k, float3 acc, int kept, float3 acc_sq, int rays)
{
    float4 s = sum[k], c = sum_c[k];
    add_compensated(&s, &c, (float4)(acc, (float)kept));
    sum[k] = s;
    sum_c[k] = c;
    s = sum_sq[k];
    c = sum_sq_c[k];
    add_compensated(&s, &c, (float4)(acc_sq, (float)rays));
    sum_sq[k] = s;
    sum_sq_c[k] = c;
}

/* The entry of `results` (add_queued_paths) of a launch's sample of pixel (x, y). */
int result_index(const RenderParams *p, uint x, uint y, uint sample)
{
    return (y * p->width + x) * p->sample_count + (sample - p->sample_start);
}

/* One work-item per pixel of rows [row_start, row_end) (a band of a pass, or all of them) adds
 * p.sample_count samples to the pixel's running sums (add_to_pixel). A NaN or infinite sample
 * (a bug, or a scene beyond float32) is left out, so that it cannot poison the pixel for the
 * rest of the render; the host counts the samples left out from w (Renderer.dropped_samples)
 * and reports them. Renderer.mean() divides by the samples taken, counting one left out as
 * black; the viewer (shaders/display.frag) and per_pixel_mean divide by those kept. A sample whose path waits in the continuation
 * queue (PATH_QUEUE) is added by add_queued_paths, from its entry of `results`: w holds the
 * rays its path traced after it was queued, as int bits, or -1 where the path was not queued. */
void render_pixel(const SceneData *sc, const RenderParams *p, global float4 *sum,
                  global float4 *sum_sq, global float4 *sum_c, global float4 *sum_sq_c,
                  PathQueue queue, global float4 *results, const int nee)
{
    int x = get_global_id(0), y = p->row_start + get_global_id(1);
    if (x >= p->width || y >= p->row_end)
        return;
    float3 acc = (float3)(0.0f), acc_sq = (float3)(0.0f);
    int rays = 0, kept = 0;
    for (uint i = 0; i < p->sample_count; ++i) {
        Rng rng = make_rng(x, y, p->sample_start + i, p->seed);
        LOG_SAMPLE(sc, i);
        CameraRay ray = sample_camera_ray(p, x, y, &rng);
        PathRecord start = start_path(p, ray.o, ray.d, &rng);
        int queued = 0;
        float3 l = trace_path(sc, p, &start, &rng, &rays, nee, queue, &queued);
#ifdef PATH_QUEUE
        if (queue.capacity > 0)
            results[result_index(p, x, y, p->sample_start + i)] = (float4)((float3)(0.0f), as_float(queued - 1));
#endif
        if (!queued)
            add_sample(l, &acc, &acc_sq, &kept);
    }
#ifdef TRAVERSAL_STATS
    rays = *sc->work;         /* the work counted stands in for the rays traced */
#endif
    add_to_pixel(sum, sum_sq, sum_c, sum_sq_c, y * p->width + x, acc, kept, acc_sq, rays);
}

/* queue, counters, queue_capacity, results: PATH_QUEUE's continuation queue, which paths enter
 * before their vertex PATH_QUEUE + 1, its count being counters[0] (queue_capacity 0: no queue);
 * with PATH_SORT, three more: the queue's keys, their counts and cell size (SORT_KERNEL_ARGS,
 * kernels/path_sort.cl); in the divergence stats build, a last argument: the records' buffer
 * (kernels/divergence.cl) */
#ifdef PATH_QUEUE
#define FIRST_QUEUED_VERTEX (PATH_QUEUE + 1)
#else
#define FIRST_QUEUED_VERTEX 0
#endif
#define RENDER_KERNEL(name, nee)                                                                 \
    kernel void name(SCENE_KERNEL_ARGS, const RenderParams p, global float4 *sum,                 \
                     global float4 *sum_sq, global float4 *sum_c, global float4 *sum_sq_c,       \
                     global float4 *queue, volatile global int *counters, int queue_capacity,     \
                     global float4 *results SORT_KERNEL_ARGS LOG_KERNEL_ARG)                     \
    {                                                                                            \
        SceneData sc = SCENE_DATA(p.num_spheres, p.layout);                                      \
        COUNT_WORK_INTO(sc);                                                                     \
        LOG_SHADING_INTO(sc);                                                                    \
        PathQueue q = {queue, counters, queue_capacity, FIRST_QUEUED_VERTEX SORT_QUEUE(0)};     \
        render_pixel(&sc, &p, sum, sum_sq, sum_c, sum_sq_c, q, results, nee);                    \
    }

#ifdef PATH_QUEUE
/* Queued path i of pass `pass` (counters[pass] of them in `queue`, entered by the launch of
 * parameters p): traces it on for `steps` vertices, where it waits again in `next` (counted by
 * counters[pass + 1]) if it goes on and `next` has room, or to its end (steps 0). Each pass adds
 * the rays it traced to the path's entry of `results`, and the pass that ends the path leaves its
 * radiance there. */
void continue_path(const SceneData *sc, const RenderParams *p, const global float4 *queue, int i,
                   PathQueue next, int steps, global float4 *results, const int nee)
{
    PathRecord start = load_path(queue, next.capacity, i);
    Rng rng = make_rng(start.rng.x, start.rng.y, start.rng.z, p->seed);
    rng.dim = start.rng.w;
    next.depth = steps > 0 ? as_int(start.throughput.w) + steps : -1;
    LOG_RESUME(sc, as_int(start.throughput.w) - 1);   /* its next iteration: the vertex's */
    int rays = 0, queued = 0;
    float3 l = trace_path(sc, p, &start, &rng, &rays, nee, next, &queued);
#ifdef TRAVERSAL_STATS
    rays = *sc->work;
#endif
    int k = result_index(p, start.rng.x, start.rng.y, start.rng.z);
    rays += as_int(results[k].w);
    results[k] = (float4)(queued ? (float3)(0.0f) : l, as_float(rays));
}

/* One work-item per path the launch could have queued; those beyond the paths in the queue end
 * at once (the host does not wait to read how many there are). With PATH_SORT, work-item i takes
 * the path in slot order[i] (CONTINUE_SORT_ARGS, kernels/path_sort.cl: sort_paths), so that
 * neighbouring work-items trace like rays. */
#define CONTINUE_KERNEL(name, nee)                                                               \
    kernel void name(SCENE_KERNEL_ARGS, const RenderParams p, const global float4 *queue,        \
                     global float4 *next, volatile global int *counters, int pass,                \
                     int queue_capacity, int steps, global float4 *results                       \
                     CONTINUE_SORT_ARGS LOG_KERNEL_ARG)                                          \
    {                                                                                            \
        SceneData sc = SCENE_DATA(p.num_spheres, p.layout);                                      \
        COUNT_WORK_INTO(sc);                                                                     \
        LOG_SHADING_INTO(sc);                                                                    \
        PathQueue q = {next, counters + pass + 1, queue_capacity, 0 SORT_QUEUE(pass + 1)};       \
        if (get_global_id(0) < min(counters[pass], queue_capacity))                              \
            continue_path(&sc, &p, queue, QUEUE_SLOT(get_global_id(0)), q, steps, results, nee); \
    }

/* One work-item per pixel, after the passes of continue_paths: adds the launch's samples of the
 * pixel whose paths were queued, in the order of the samples, so that the sums do not depend on
 * the order in which the queues were filled. */
kernel void add_queued_paths(const RenderParams p, global float4 *sum, global float4 *sum_sq,
                             global float4 *sum_c, global float4 *sum_sq_c,
                             const global float4 *results)
{
    int x = get_global_id(0), y = p.row_start + get_global_id(1);
    if (x >= p.width || y >= p.row_end)
        return;
    float3 acc = (float3)(0.0f), acc_sq = (float3)(0.0f);
    int rays = 0, kept = 0, queued = 0;
    for (uint i = 0; i < p.sample_count; ++i) {
        float4 l = results[result_index(&p, x, y, p.sample_start + i)];
        if (as_int(l.w) < 0)
            continue;
        ++queued;
        rays += as_int(l.w);
        add_sample(l.xyz, &acc, &acc_sq, &kept);
    }
    if (queued)
        add_to_pixel(sum, sum_sq, sum_c, sum_sq_c, y * p.width + x, acc, kept, acc_sq, rays);
}
#endif

/* With TRAVERSAL_STATS the render kernels count the work of their rays' traversals into a
 * counter of their own, which each pixel reports in place of its rays. */
#ifdef TRAVERSAL_STATS
#define COUNT_WORK_INTO(sc) int work_ = 0; (sc).work = &work_
#else
#define COUNT_WORK_INTO(sc)
#endif

/* render: the report's estimator; render_nee: with next-event estimation. A program holds the
 * ones its renders launch (app/device/features.py: KERNEL_SETS). */
#ifdef ENTRY_RENDER
RENDER_KERNEL(render, 0)
#ifdef PATH_QUEUE
CONTINUE_KERNEL(continue_paths, 0)
#endif
#endif
#ifdef ENTRY_RENDER_NEE
RENDER_KERNEL(render_nee, 1)
#ifdef PATH_QUEUE
CONTINUE_KERNEL(continue_paths_nee, 1)
#endif
#endif

/* The nearest primitive along one ray, or -1, and its distance (the viewer's picking and
 * focusing): hit[0] the primitive, hit[1] the distance's float bits. */
#ifdef ENTRY_AUX
kernel void pick(SCENE_KERNEL_ARGS, int num_spheres, int layout, float4 o, float4 d, global int *hit)
{
    SceneData sc = SCENE_DATA(num_spheres, layout);
    Hit h = intersect_scene(&sc, o.xyz, normalize(d.xyz), INFINITY, NO_PRIM);
    hit[0] = h.prim;
    hit[1] = as_int(h.t);
}
#endif
