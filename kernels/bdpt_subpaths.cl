/* The subpaths of bidirectional path tracing (kernels/bdpt.cl): a camera subpath from the
 * lens and a light subpath from a light chosen by power, each vertex storing the densities with
 * which its own subpath and the other end would draw it (kernels/bdpt_vertex.cl), as pbrt-v4's
 * RandomWalk and GenerateLightSubpath store theirs. */

/* The density per area with which a light subpath starts at point y of emissive primitive
 * `prim` (the light's choice by power times its area's inverse, pbrt's PdfLightOrigin, or an
 * analytic shape's density there), and *n, the unit normal on its front there. */
float emitter_at(const SceneData *sc, int prim, float3 y, float3 *n)
{
#ifndef NO_TRIANGLES
    if (prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[prim - sc->num_spheres];
#ifdef SHAPES
        if (SHAPE_KIND(tri)) {
            const global float4 *f = SHAPE_ROWS(sc, tri);
            float2 params = analytic_params(SHAPE_KIND(tri), f, y);
            float3 p, error;
            analytic_surface(SHAPE_KIND(tri), f, params, &p, &error, n);
            return sc->light_pick[prim] * analytic_pdf_area(SHAPE_KIND(tri), f, params);
        }
#endif
        *n = triangle_normal(tri);
        return sc->light_pick[prim] / triangle_area(tri);
    }
#endif
    Sphere s = sc->spheres[prim];
    *n = (y - s.xyz) / s.w;
    return sc->light_pick[prim] / (4.0f * PI_F * s.w * s.w);
}

/* Traces subpath `path` on from its vertex k - 1 along the ray o + t d (leaving surface `self`,
 * in `medium`), whose direction was drawn with density pdf_dir per solid angle (0: a delta
 * lobe), with throughput beta, to at most max_vertices vertices; returns its vertex count.
 * Each new vertex stores its forward density, and the reverse density of the one before it. A
 * camera subpath (importance 0) that escapes to a lit environment ends on a vertex at infinity,
 * the environment's; a light subpath (importance 1) scatters by the adjoint BSDFs. */
int extend_subpath(const SceneData *sc, const RenderParams *p, Vertex *path, int k, int max_vertices,
                   float3 o, float3 d, float3 beta, float pdf_dir, PrimId self, int medium, const int importance,
                   Rng *rng, int *rays)
{
    while (k < max_vertices) {
        Vertex *prev = &path[k - 1], *v = &path[k];
        ++*rays;
        Hit hit = intersect_scene(sc, o, d, INFINITY, self);
#ifdef MEDIA
        v->medium = medium;
        v->in_medium = 0;
        if (medium >= 0) {
            const global Medium *med = &sc->media[medium];
            float4 u = next_uniform4(rng);
            FreeFlight flight = sample_free_flight(med, hit.t, min((int)(3.0f * u.x), 2), u.y);
            beta *= flight.weight / dot(flight.ratio, (float3)(1.0f / 3.0f));
            if (flight.scattered) {
                v->s.p = o + flight.t * d;
                v->s.ng = v->s.ns = (float3)(0.0f);
                v->s.offset = 0.0f;
                v->s.prim = -1;
#ifdef INSTANCES
                v->s.instance = -1;
#endif
                v->in_medium = 1;
                v->wo = -d;
                v->beta = beta;
                v->pdf_fwd = convert_density(pdf_dir, prev->s.p, v->s.p, v->s.ng);
                v->pdf_rev = 0.0f;
                v->delta = 0;
                v->connectible = 1;
                v->emits = 0;
                v->at_infinity = 0;
                if (++k >= max_vertices || all(beta == 0.0f))
                    return k;
                /* the phase function is sampled exactly (weight 1) and is symmetric: the
                   reverse density is the forward one */
                d = sample_hg(med->sigma_s.w, -d, u.zw, &pdf_dir);
                prev->pdf_rev = density_at(pdf_dir, v->s.p, prev);
                o = v->s.p;
                self = NO_PRIM;
                continue;
            }
        }
#endif
        if (hit.prim < 0) {
            /* only a lit environment, which is a light (p->env_pick > 0), ends a camera subpath */
            if (importance || !(p->env_pick > 0.0f))
                return k;
            v->s.p = o;
            v->s.ng = v->s.ns = (float3)(0.0f);
            v->s.prim = -1;
            v->wo = -d;
            v->beta = beta;
            v->pdf_fwd = pdf_dir;
            v->pdf_rev = 0.0f;
            v->delta = 0;
            v->connectible = 0;
            v->emits = 1;
            v->at_infinity = 1;
#ifdef MEDIA
            v->medium = medium;
            v->in_medium = 0;
#endif
            return k + 1;
        }
        Surface s = surface_at(sc, &hit, o, d);
        int flags = sc->materials[sc->prim_material[hit.prim]].flags;
#ifdef NULL_SURFACES
        if (flags & MATERIAL_NULL) {
            /* no vertex: the ray goes on through, into the medium beyond */
            medium = medium_after(sc, &s, d, medium);
            o = offset_ray_origin(s.p, s.offset, s.ng, d);
            self = HIT_ID(hit);
            continue;
        }
#endif
        int front = dot(s.ng, d) < 0.0f;
        /* one-sided, as the path tracer's surfaces (kernels/integrator.cl: trace_path) */
        int scatters = front || (flags & (MATERIAL_TWOSIDED | MATERIAL_TRANSMISSIVE));
        if (!front && (flags & MATERIAL_TWOSIDED))
            turn_round(&s);
#ifdef TEXTURES
        v->m = shade_material(sc, MATERIAL_ROW(sc, s, d), &s);
#else
        v->m = MATERIAL_ROW(sc, s, d);
#endif
        complete_frame(sc, &s);
        v->s = s;
        v->wo = -d;
        v->beta = beta;
        v->pdf_fwd = convert_density(pdf_dir, prev->s.p, s.p, s.ng);
        v->pdf_rev = 0.0f;
        v->delta = 0;
        v->at_infinity = 0;
        MaterialRef m = VERTEX_MATERIAL(v);
        v->emits = front || (flags & MATERIAL_EMITS_BACK);
        v->connectible = scatters && !(m->flags & MATERIAL_DELTA);
        if (!scatters || k + 1 >= max_vertices)
            return k + 1;
        float4 u = next_uniform4(rng);
        /* f, the frame it scatters in, is the one the camera's side sees (seen_from): on a
           camera subpath the ray's; on a light subpath one drawn before the direction, which
           must then see it (frame_probability). p_frame: the probability of drawing f;
           p_frame_rev: a light subpath's of drawing a camera subpath's f */
        Surface f = s;
        float p_frame = 1.0f, p_frame_rev = 1.0f;
#ifdef NORMAL_MAPS
        int turned = importance ? u.w < frame_probability(&s, 1) : turns_perturbed_normal(&s, -d);
        if (turned) {
            turn_perturbed_normal(&f);
            complete_frame(sc, &f);
        }
        if (importance)
            p_frame = frame_probability(&s, turned);
        else
            p_frame_rev = frame_probability(&s, turned);
#endif
        float3 wo = to_shading(&f, -d);
        BSDFSample bs;
        bs.eta = 1.0f;
        if (!sample_bsdf(m, wo, u.xyz, &bs))
            return k + 1;
        float3 wi = from_shading(&f, bs.wi);
        /* light arrives along -d on a light subpath, along wi on a camera subpath */
        if (importance ? !carries_light(&f, flags & MATERIAL_TRANSMISSIVE, wi, bs.wi)
                           || !PERTURBED_SIDES_AGREE(&f, -d, wo.z)
                       : !carries_light(&f, flags & MATERIAL_TRANSMISSIVE, -d, wo)
                           || !PERTURBED_SIDES_AGREE(&f, wi, bs.wi.z))
            return k + 1;
#ifdef NORMAL_MAPS
        if (importance && turns_perturbed_normal(&s, wi) != turned)
            return k + 1;                    /* wi sees the other frame */
#endif
        /* importance scatters by the adjoint BSDF f(wi, wo): in one frame the BSDFs are
           reciprocal but for a refraction's 1 / eta^2, which radiance takes and importance not (pbrt's
           TransportMode), so its weight is radiance's times eta^2; a layered BSDF's estimate
           (kernels/layered.cl) keeps this form, where f(wi, wo) / pdf would not */
        float3 weight = bs.weight / p_frame;
        if (importance)
            weight *= bs.eta * bs.eta * correct_shading_normal(&f, -d, wi);
#ifdef NORMAL_MAPS
        /* the path tracer shadows the direction light arrives from (eval_scattering): on a light
           subpath the one it came along, on a camera subpath the one sampled */
        weight *= shadow_terminator(&s, importance ? -d : wi);
#endif
        float pdf_rev = 0.0f;
        if (bs.lobe & LOBE_DELTA) {
            v->delta = 1;
            pdf_dir = 0.0f;
        } else {
            pdf_dir = bs.pdf * p_frame;
            pdf_rev = pdf_bsdf(m, bs.wi, wo) * p_frame_rev;
        }
        beta *= weight;
        if (all(beta == 0.0f))
            return k + 1;
        prev->pdf_rev = density_at(pdf_rev, s.p, prev);
        o = offset_ray_origin(s.p, s.offset, s.ng, wi);
        d = wi;
        self = HIT_ID(hit);
#ifdef MEDIA
        medium = medium_after(sc, &s, wi, medium);
#endif
        ++k;
    }
    return k;
}

/* A light subpath in lt (at most max_vertices vertices, the light's own first): a light
 * chosen by power through the alias table, light leaving it (emit_light_of_type); returns its
 * vertex count, 0 where the light chosen starts none. *light_delta: its position or direction
 * is a delta. */
int trace_light_subpath(const SceneData *sc, const RenderParams *p, Vertex *lt, int max_vertices, Rng *rng,
                        int *rays, int *light_delta)
{
    uint4 r = next_bits4(rng);
    float4 u = next_uniform4(rng);
    if (p->num_lights <= 0 || max_vertices < 1)
        return 0;
    const global Light *l = &sc->lights[pick_light(sc->lights, p->num_lights, r.w, r.x)];
    LightEmission e;
    e.at_infinity = 0;
    if (!emit_light_of_type(sc, p, l, u, &e) || all(e.le == 0.0f))
        return 0;
    float origin = l->pick * e.pdf_pos;
    lt[0].s.p = e.p;
    lt[0].s.ng = e.n;
    lt[0].s.prim = e.prim;
    lt[0].s.offset = e.offset;
#ifdef INSTANCES
    lt[0].s.instance = -1;
#endif
    lt[0].beta = e.le;
    /* a light at infinity's vertex is its direction, drawn with the choice times pdf_dir (pbrt's
       InfiniteLightDensity) */
    lt[0].pdf_fwd = e.at_infinity ? l->pick * e.pdf_dir : origin;
    lt[0].pdf_rev = 0.0f;
    lt[0].delta = 0;
    lt[0].connectible = 0;
    lt[0].emits = 0;
    lt[0].at_infinity = e.at_infinity;
#ifdef MEDIA
    /* e.n is on the side light leaves, which for an emitter of both sides may be its back */
    float3 front = e.n;
    if (e.prim >= 0)
        emitter_at(sc, e.prim, e.p, &front);
    lt[0].s.side = dot(e.n, front) < 0.0f ? -1.0f : 1.0f;
    lt[0].in_medium = 0;
    /* where the emitter bounds media, medium_towards reads its side; elsewhere the light is in
       the medium around it */
    lt[0].medium = e.prim >= 0 && sc->prim_media[e.prim] != NO_MEDIUM_CHANGE
                   ? -1 : medium_at(sc, p->eye.xyz, p->camera_medium, e.p, rays);
    /* light from infinity crosses an unbounded medium with transmittance 0, as the path tracer's
       shadow rays find: none reaches the scene */
    if (e.at_infinity && lt[0].medium >= 0)
        return 0;
#endif
    *light_delta = e.delta;
    float c = e.prim >= 0 ? fabs(dot(e.n, e.d)) : 1.0f;
    float3 beta = e.le * (c / (origin * e.pdf_dir));
    float3 o = e.prim >= 0 ? offset_ray_origin(e.p, e.offset, e.n, e.d) : e.p;
#ifdef INSTANCES
    PrimId self = NO_PRIM;    /* the light table's primitives are not instanced */
#else
    PrimId self = e.prim >= 0 ? e.prim : NO_PRIM;
#endif
    int n = extend_subpath(sc, p, lt, 1, max_vertices, o, e.d, beta, e.pdf_dir, self, medium_towards(sc, &lt[0], e.d),
                           1, rng, rays);
    /* light from infinity reaches its first hit with the disk's density per area (pbrt-v4's
       GenerateLightSubpath), not by a direction's from a point */
    if (e.at_infinity && n > 1)
        lt[1].pdf_fwd = density_from_infinity(p, e.d, &lt[1]);
    return n;
}
