/* Bidirectional path tracing (Veach 1997, chapter 10; the conventions of pbrt-v4's
 * src/pbrt/cpu/integrators.cpp BDPTIntegrator and pbrt-v3's bdpt.cpp): for each sample, a camera
 * subpath from the pixel and a light subpath from a light chosen by power, then every connection
 * (s light vertices, t camera vertices) of total depth at most BDPT, the program's longest path
 * (app/device/features.py), each weighted by multiple importance sampling (power heuristic) over the
 * strategies that could have drawn the same path, from the forward and reverse densities the
 * vertices store (bdpt_mis_weight), as pbrt does, not by drawing each strategy again; the sums
 * of the densities' ratios along each subpath are accumulated once per subpath (sum_mis_ratios).
 *
 * A path's vertices: the camera (or the light) is vertex 0 of its subpath; a path of s + t
 * vertices has depth s + t - 1 in the path tracer's sense (kernels/integrator.cl: the camera
 * ray's hit is depth 1, max_depth the last vertex, which only emits).
 *
 *   t >= 2, s = 0   the camera subpath hits an emitter (or escapes to the environment)
 *   t >= 2, s = 1   a light sampled from camera vertex t - 1, as next-event estimation does
 *   t >= 2, s >= 2  light vertex s - 1 joined to camera vertex t - 1 by a shadow ray
 *   t = 1, s >= 2   light vertex s - 1 joined to the lens (light tracing): its contribution
 *                   lands in another pixel, added to the launch's splat film by atomics
 *
 * Delta lobes are not joined (their vertices are not connectible) and delta lights are not hit,
 * as in pbrt; the lens (a pinhole or a thin lens) is reached by joins, never by a light subpath
 * hitting it (t = 0, which pbrt leaves out too).
 * The environment and directional lights start light subpaths too, from a disk across the
 * scene (kernels/lights.cl: leave_world_disk), and their vertices are directions, whose
 * densities are per solid angle, as pbrt-v4's infinite lights' are (kernels/bdpt_vertex.cl:
 * at_infinity): a camera subpath that escapes ends on such a vertex (s = 0), and a light
 * subpath's second vertex is drawn with the disk's density per area times its cosine. There is
 * no Russian roulette (pbrt-v4's BDPT has none): paths
 * end at depth BDPT. Light subpaths carry importance: BSDFs are evaluated as their adjoints
 * (arguments swapped, kernels/bsdf.cl's radiance convention), a delta refraction keeps the eta^2
 * that radiance loses, and shading normals are corrected as Veach's section 5.3 says.
 *
 * In a scene with participating media (MEDIA), both subpaths sample free flights in the media
 * they cross, as the path tracer does, and a scattering inside a medium is a vertex like a
 * surface's, its phase function in place of a BSDF, with no cosine; connections carry the
 * transmittance along them, across null boundaries (kernels/volume.cl), and null surfaces are
 * no vertices (Veach's volumetric path space; pbrt-v4's BDPT RandomWalk). A free flight's
 * density is the mean of the three channels' (its hero channel drawn uniformly per flight: the
 * balance heuristic over channels, per event), a scalar as the vertices' densities must be; the
 * MIS weights leave the distances' densities out, as pbrt's do: the weights of a path's
 * strategies still sum to 1.
 *
 * With PHOTONS, the paths that only s = 0 samples and only by chance (a surface seen and lit
 * through delta bounces alone) are left to caustic photons instead (kernels/photons.cl). */

/* The fraction of light that crosses the segment from vertex a to point b: 0 or 1 by whether
 * anything blocks it (b itself excluded, stopping just short of it as light_visibility does),
 * or with media the transmittance along it. */
float3 segment_transmittance(const SceneData *sc, const Vertex *a, float3 b, int *rays)
{
    float3 w = b - a->s.p;
    float3 o = offset_ray_origin(a->s.p, a->s.offset, a->s.ng, w);
    float dist = norm(b - o);
    float3 d = (b - o) / dist;
    ++*rays;
#ifdef MEDIA
    return transmittance_along(sc, o, d, dist * (1.0f - SHADOW_EPSILON), SURFACE_ID(a->s), medium_towards(sc, a, w),
                               rays);
#else
    return occluded(sc, o, d, dist * (1.0f - SHADOW_EPSILON), SURFACE_ID(a->s)) ? (float3)(0.0f) : (float3)(1.0f);
#endif
}

/* The reverse densities of bdpt_mis_weight (camera vertices t - 1 and t - 2, light vertices
 * s - 1 and s - 2) for each kind of connection: pbrt's Vertex::Pdf and PdfLight, PdfLightOrigin
 * as pbrt-v4's MISWeight assigns them. */

/* s = 0: camera vertex pt, after pm, lies on an emitter, or is the environment's at infinity. */
float4 densities_from_emitter(const SceneData *sc, const RenderParams *p, const Vertex *pt, const Vertex *pm)
{
    if (pt->at_infinity) {
        float3 d = -pt->wo;
        return (float4)(p->env_pick * pdf_environment_emission(sc, p, d), density_from_infinity(p, d, pm), 0.0f, 0.0f);
    }
    int prim = pt->s.prim;
    float3 n;
    float origin = emitter_at(sc, prim, pt->s.p, &n);
    return (float4)(origin,
                    convert_density(pdf_area_emission(sc, prim, n, pt->wo), pt->s.p, pm->s.p, pm->s.ng), 0.0f, 0.0f);
}

/* s = 1: light l sampled at point y (normal n, 0 for a point) from camera vertex pt, after pm. */
float4 densities_to_light(const SceneData *sc, const RenderParams *p, const global Light *l, float3 y, float3 n,
                          const Vertex *pt, const Vertex *pm)
{
    float3 wi = unit(y - pt->s.p);
    return (float4)(convert_density(pdf_emission_of_type(sc, p, l, n, -wi), y, pt->s.p, pt->s.ng),
                    convert_density(pdf_scattering(sc, pt, wi, pt->wo, 1), pt->s.p, pm->s.p, pm->s.ng),
                    convert_density(pdf_scattering(sc, pt, pt->wo, wi, 0), pt->s.p, y, n), 0.0f);
}

/* s = 1: a light at infinity sampled in direction wi from camera vertex pt, after pm. */
float4 densities_to_infinity(const SceneData *sc, const RenderParams *p, float3 wi, const Vertex *pt,
                             const Vertex *pm)
{
    return (float4)(density_from_infinity(p, -wi, pt),
                    convert_density(pdf_scattering(sc, pt, wi, pt->wo, 1), pt->s.p, pm->s.p, pm->s.ng),
                    pdf_scattering(sc, pt, pt->wo, wi, 0), 0.0f);
}

/* s >= 2, t >= 2: light vertex qs, after qm, joined to camera vertex pt, after pm. */
float4 densities_between(const SceneData *sc, const Vertex *qs, const Vertex *qm, const Vertex *pt,
                         const Vertex *pm)
{
    float3 w = unit(qs->s.p - pt->s.p);
    return (float4)(convert_density(pdf_scattering(sc, qs, qs->wo, -w, 1), qs->s.p, pt->s.p, pt->s.ng),
                    convert_density(pdf_scattering(sc, pt, w, pt->wo, 1), pt->s.p, pm->s.p, pm->s.ng),
                    convert_density(pdf_scattering(sc, pt, pt->wo, w, 0), pt->s.p, qs->s.p, qs->s.ng),
                    density_at(pdf_scattering(sc, qs, -w, qs->wo, 0), qs->s.p, qm));
}

/* t = 1: light vertex qs, after qm, joined to the lens at point `lens`. */
float4 densities_to_camera(const SceneData *sc, const RenderParams *p, const Vertex *qs, const Vertex *qm,
                           float3 lens)
{
    float3 w = unit(lens - qs->s.p);
    return (float4)(0.0f, 0.0f,
                    convert_density(pdf_camera_direction(p, -w), lens, qs->s.p, qs->s.ng),
                    density_at(pdf_scattering(sc, qs, w, qs->wo, 0), qs->s.p, qm));
}

/* Strategy s = 0: camera vertex t - 1 (t >= 2) lies on an emitter; the radiance it sends back
 * along the camera subpath, weighted. */
float3 connect_emitter(const SceneData *sc, const RenderParams *p, const Vertex *lt, const Vertex *cam, int t)
{
    const Vertex *pt = &cam[t - 1], *pm = &cam[t - 2];
    if (!pt->emits)
        return (float3)(0.0f);
#ifdef PHOTONS
    if (photons_estimate(cam, t))
        return (float3)(0.0f);        /* the photons count this path (kernels/photons.cl) */
#endif
    float3 le = pt->at_infinity ? lookup_environment(sc->env, p, -pt->wo) : VERTEX_MATERIAL(pt)->emission.xyz;
    if (all(le == 0.0f))
        return (float3)(0.0f);
    return pt->beta * le * bdpt_mis_weight(lt, 0, cam, t, densities_from_emitter(sc, p, pt, pm), 0.0f, 0);
}

/* Strategy s = 1: a light sampled from camera vertex t - 1 (t >= 2), as next-event estimation
 * samples one (kernels/lights.cl: sample_light, by power), weighted; its vertex's densities are
 * a light subpath's first (trace_light_subpath), as pbrt's are, whatever next-event estimation
 * drew it by: the weights still sum to 1 over the strategies. */
float3 connect_light_sample(const SceneData *sc, const RenderParams *p, const Vertex *lt, const Vertex *cam,
                            int t, Rng *rng, int *rays)
{
    const Vertex *pt = &cam[t - 1], *pm = &cam[t - 2];
    LightSample ls = sample_light(sc, p, pt->s.p, pt->s.ns, next_bits4(rng), rng);
    if (!(ls.pdf > 0.0f))
        return (float3)(0.0f);
    float3 f = eval_scattering(sc, pt, ls.wi, pt->wo) * joined_cos(sc, pt, ls.wi, pt->wo, 0);
    float3 c = pt->beta * f * ls.le / ls.pdf;
    if (all(c == 0.0f))
        return (float3)(0.0f);
    const global Light *l = &sc->lights[ls.light];
    int delta = (ls.flags & LIGHT_DELTA) != 0;
    float w;
    if (ls.flags & LIGHT_AT_INFINITY) {
        /* its vertex is the direction -wi, drawn as a light subpath's first (trace_light_subpath) */
        float origin = l->pick * (delta ? 1.0f : pdf_environment_emission(sc, p, ls.wi));
        w = bdpt_mis_weight(lt, 1, cam, t, densities_to_infinity(sc, p, ls.wi, pt, pm), origin, delta);
    } else {
        float3 n = (float3)(0.0f);
        float origin = delta ? l->pick : emitter_at(sc, l->prim, ls.y, &n);
        w = bdpt_mis_weight(lt, 1, cam, t, densities_to_light(sc, p, l, ls.y, n, pt, pm), origin, delta);
    }
    float3 o = offset_ray_origin(pt->s.p, pt->s.offset, pt->s.ng, ls.wi);
    return c * w * light_visibility(sc, o, &ls, SURFACE_ID(pt->s), medium_towards(sc, pt, ls.wi), rays);
}

/* Strategy s >= 2, t >= 2: light vertex s - 1 joined to camera vertex t - 1, weighted;
 * light_delta: as connect_camera's. */
float3 connect_vertices(const SceneData *sc, const Vertex *lt, int s, const Vertex *cam, int t, int light_delta,
                        int *rays)
{
    const Vertex *qs = &lt[s - 1], *qm = &lt[s - 2], *pt = &cam[t - 1], *pm = &cam[t - 2];
    float3 w = qs->s.p - pt->s.p;
    float d2 = dot(w, w);
    if (!(d2 > 0.0f))
        return (float3)(0.0f);
    w *= rsqrt(d2);
    /* radiance flows from qs's past through qs, along -w to pt, and on to pt's past */
    float3 f_q = eval_scattering(sc, qs, qs->wo, -w) * joined_cos(sc, qs, qs->wo, -w, 1);
    float3 f_p = eval_scattering(sc, pt, w, pt->wo) * joined_cos(sc, pt, w, pt->wo, 0);
    float3 c = qs->beta * f_q * f_p * pt->beta / d2;
    if (all(c == 0.0f))
        return (float3)(0.0f);
    c *= bdpt_mis_weight(lt, s, cam, t, densities_between(sc, qs, qm, pt, pm), 0.0f, light_delta);
    return c * segment_transmittance(sc, pt, qs->s.p, rays);
}

/* Strategy t = 1, s >= 2: light vertex s - 1 joined to a point of the lens (kernels/camera.cl:
 * sample_importance), splatted where it lands on the film; weighted, or with LIGHT_TRACING
 * alone. light_delta: the light subpath's light is a delta (bdpt_mis_weight). */
void connect_camera(const SceneData *sc, const RenderParams *p, const Vertex *lt, int s, const Vertex *cam,
                    int light_delta, Rng *rng, global float4 *film, int *rays)
{
    const Vertex *qs = &lt[s - 1], *qm = &lt[s - 2];
    CameraImportance ci;
    if (!sample_importance(p, qs->s.p, next_uniform4(rng).xy, &ci))
        return;
    float3 w = unit(ci.lens - qs->s.p);           /* towards the lens */
    float3 f = eval_scattering(sc, qs, qs->wo, w) * joined_cos(sc, qs, qs->wo, w, 1);
    float3 c = qs->beta * f * ci.weight;
    if (all(c == 0.0f) || !all(isfinite(c)))
        return;
#ifndef LIGHT_TRACING
    c *= bdpt_mis_weight(lt, s, cam, 1, densities_to_camera(sc, p, qs, qm, ci.lens), 0.0f, light_delta);
#endif
    c *= segment_transmittance(sc, qs, ci.lens, rays);
    if (any(c != 0.0f))
        splat(film, p, ci.at, c);
}

#ifdef LIGHT_TRACING
/* Strategy s = 1, t = 1 of light tracing alone: the point a light subpath leaves an area light
 * from, seen by the camera (Mitsuba 3's ptracer sees emitters so); a point or spot light, which
 * no camera ray sees either, is not. */
void connect_light_to_camera(const SceneData *sc, const RenderParams *p, const Vertex *light, Rng *rng,
                             global float4 *film, int *rays)
{
    int prim = light->s.prim;
    CameraImportance ci;
    if (prim < 0 || !sample_importance(p, light->s.p, next_uniform4(rng).xy, &ci))
        return;
    float3 n;
    emitter_at(sc, prim, light->s.p, &n);
    float cos_l = dot(n, unit(ci.lens - light->s.p));
    if (emits_back(sc, prim))
        cos_l = fabs(cos_l);
    if (!(cos_l > 0.0f))
        return;
    /* Le cos_l / pdf_origin, times the lens's weight as in connect_camera */
    float3 c = light->beta * (cos_l * ci.weight / light->pdf_fwd);
    if (all(isfinite(c)))
        c *= segment_transmittance(sc, light, ci.lens, rays);
    if (all(isfinite(c)) && any(c != 0.0f))
        splat(film, p, ci.at, c);
}

/* One sample of light tracing alone (Mitsuba 3's ptracer): a light subpath, each of its
 * vertices joined to the lens with weight 1; no camera subpath, the pixel's own radiance 0. */
float3 sample_light_tracing(const SceneData *sc, const RenderParams *p, Rng *rng, global float4 *film, int *rays)
{
    Vertex lt[BDPT_LIGHT_VERTICES];
    int light_delta = 0;
    int nl = trace_light_subpath(sc, p, lt, BDPT_LIGHT_VERTICES, rng, rays, &light_delta);
    if (nl > 0 && !lt[0].at_infinity)      /* a light at infinity is no point to see */
        connect_light_to_camera(sc, p, &lt[0], rng, film, rays);
    for (int s = 2; s <= nl; ++s)
        if (lt[s - 1].connectible)
            connect_camera(sc, p, lt, s, 0, light_delta, rng, film, rays);
    return (float3)(0.0f);
}
#endif

/* One sample of pixel (x, y): its camera subpath's strategies (t >= 2) as the radiance
 * returned (with PHOTONS, and the caustic photons it gathers), the light tracing of its light
 * subpath (t = 1) splatted. */
float3 sample_bidirectional(const SceneData *sc, const RenderParams *p, int x, int y, Rng *rng,
                            global float4 *film, int *rays
#ifdef PHOTONS
                            , global const Photon *photons, global const int *photon_next,
                            global const int *photon_heads, const PhotonMap *map
#endif
                            )
{
    Vertex cam[BDPT_CAMERA_VERTICES], lt[BDPT_LIGHT_VERTICES];
    CameraRay ray = sample_camera_ray(p, x, y, rng);
    cam[0].s.p = ray.o;
    cam[0].s.ng = (float3)(0.0f);
    cam[0].beta = (float3)(1.0f);
    cam[0].pdf_fwd = 1.0f;
    cam[0].pdf_rev = 0.0f;
    cam[0].delta = 0;
    cam[0].connectible = 0;
    cam[0].emits = 0;
    cam[0].at_infinity = 0;
    cam[0].s.prim = -1;
#ifdef MEDIA
    cam[0].medium = p->camera_medium;
    cam[0].in_medium = 0;
#endif
    int nc = extend_subpath(sc, p, cam, 1, BDPT_CAMERA_VERTICES, ray.o, ray.d, (float3)(1.0f),
                            pdf_camera_direction(p, ray.d), NO_PRIM, medium_towards(sc, &cam[0], ray.d), 0, rng,
                            rays);
    int light_delta = 0;
    int nl = trace_light_subpath(sc, p, lt, BDPT_LIGHT_VERTICES, rng, rays, &light_delta);
    sum_mis_ratios(cam, nc, 1, 0);
    sum_mis_ratios(lt, nl, 0, light_delta);
    float3 l = (float3)(0.0f);
#ifdef PHOTONS
    l += caustic_radiance(sc, cam, nc, photons, photon_next, photon_heads, map);
#endif
    /* s = 1 samples a light of its own, with or without a light subpath */
    int s_max = max(nl, 1);
    for (int t = 1; t <= nc; ++t) {
        for (int s = 0; s <= s_max; ++s) {
            if (s + t < 2 || s + t > BDPT + 1 || (s == 1 && t == 1))
                continue;
            if (t == 1) {
                if (lt[s - 1].connectible)
                    connect_camera(sc, p, lt, s, cam, light_delta, rng, film, rays);
            } else if (s == 0) {
                l += connect_emitter(sc, p, lt, cam, t);
            } else if (s == 1) {
                if (cam[t - 1].connectible && p->num_lights > 0)
                    l += connect_light_sample(sc, p, lt, cam, t, rng, rays);
            } else if (cam[t - 1].connectible && lt[s - 1].connectible) {
                l += connect_vertices(sc, lt, s, cam, t, light_delta, rays);
            }
        }
    }
    return l;
}

/* One work-item per pixel of rows [row_start, row_end) adds p.sample_count samples to the
 * pixel's running sums, as render_pixel does (kernels/integrator.cl), and splats its light
 * subpaths' contributions onto `film`, which add_splats then adds to the sums. */
kernel void render_bdpt(SCENE_KERNEL_ARGS, const RenderParams p, global float4 *sum, global float4 *sum_sq,
                        global float4 *sum_c, global float4 *sum_sq_c, global float4 *film PHOTON_ARGS)
{
    SceneData sc = SCENE_DATA(p.num_spheres, p.layout);
    COUNT_WORK_INTO(sc);
    int x = get_global_id(0), y = p.row_start + get_global_id(1);
    if (x >= p.width || y >= p.row_end)
        return;
    float3 acc = (float3)(0.0f), acc_sq = (float3)(0.0f);
    int rays = 0, kept = 0;
    for (uint i = 0; i < p.sample_count; ++i) {
        Rng rng = make_rng(x, y, p.sample_start + i, p.seed);
#ifdef LIGHT_TRACING
        add_sample(sample_light_tracing(&sc, &p, &rng, film, &rays), &acc, &acc_sq, &kept);
#else
        add_sample(sample_bidirectional(&sc, &p, x, y, &rng, film, &rays PHOTONS_PASSED), &acc, &acc_sq, &kept);
#endif
    }
#ifdef TRAVERSAL_STATS
    rays = *sc.work;
#endif
    add_to_pixel(sum, sum_sq, sum_c, sum_sq_c, y * p.width + x, acc, kept, acc_sq, rays);
}

#ifdef PHOTONS
/* One pass's caustic photons (kernels/photons.cl), one light subpath per work-item (pixel) of
 * the whole image, drawn from random numbers of their own: a photon where the subpath meets a
 * surface with more than a delta lobe after delta bounces alone. A subpath that meets several
 * (the first sampled a delta lobe of its own: a coating's mirror) leaves one of them, chosen
 * uniformly and weighted by their number, so that each has its due in expectation and the map
 * holds at most a photon per subpath. `count` counts them. */
kernel void trace_photons(SCENE_KERNEL_ARGS, const RenderParams p, global Photon *photons, global int *photon_next,
                          global int *photon_heads, global int *count, const PhotonMap map)
{
    SceneData sc = SCENE_DATA(p.num_spheres, p.layout);
    int x = get_global_id(0), y = get_global_id(1);
    if (x >= p.width || y >= p.height)
        return;
    Rng rng = make_rng(x, y, p.sample_start, ~p.seed);
    Vertex lt[BDPT_LIGHT_VERTICES];
    int rays = 0, light_delta = 0;
    int n = trace_light_subpath(&sc, &p, lt, BDPT_LIGHT_VERTICES, &rng, &rays, &light_delta);
    int landings[BDPT_LIGHT_VERTICES], m = 0;
    for (int k = 1; k < n && !in_medium(&lt[k]); ++k) {
        if (k >= 2 && lt[k].connectible)
            landings[m++] = k;
        if (!lt[k].delta)
            break;
    }
    if (m > 0) {
        int k = landings[min((int)(next_uniform4(&rng).x * m), m - 1)];
        store_photon(photons, photon_next, photon_heads, count, &map, &lt[k], k, (float)m);
    }
}
#endif

/* One work-item per pixel of the whole image, after a launch of render_bdpt: adds the launch's
 * splats to the pixel's radiance sum (compensated, counting no sample: the splats are part of
 * the samples the launch added) and clears them for the next. The sums of squares hold the
 * camera subpaths' part alone (Renderer.variance says so). */
kernel void add_splats(const RenderParams p, global float4 *sum, global float4 *sum_c, global float4 *film)
{
    int x = get_global_id(0), y = get_global_id(1);
    if (x >= p.width || y >= p.height)
        return;
    int k = y * p.width + x;
    float4 s = sum[k], c = sum_c[k];
    add_compensated(&s, &c, (float4)(film[k].xyz, 0.0f));
    sum[k] = s;
    sum_c[k] = c;
    film[k] = (float4)(0.0f);
}
