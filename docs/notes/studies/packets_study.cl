/* docs/notes/studies/packets_study.py: rays traced in packets on CPUs, an experiment (docs/notes/performance-2026-11.md,
 * 2026-11-26). Appended to a scene's program after kernels/trace_split.cl, with LANES (4, 8 or
 * 16), floatN and intN (float and int vectors of LANES), and the tile TILE_W x TILE_H of pixels
 * whose rays form one packet, defined by the script.
 *
 * A packet walks the scene's 4-wide BVH once for all its lanes: a child's box is entered where
 * any live lane enters it before that lane's nearest hit; leaves test their primitives against
 * the lanes that entered them (triangles by Moller and Trumbore's test, spheres by the
 * quadratic); inner children are pushed farthest first by their nearest lane's entry. A shadow
 * packet retires each lane at its first hit.
 *
 *   trace_packets   kernels/trace_split.cl's recorded rays of one kind, a tile per work-item;
 *                   hits and the nodes each packet visited, as trace_rays reports them
 *   render_packets  depth 8 with next-event estimation, the tile's paths in step: their rays
 *                   traced as packets, shading lane by lane with the megakernel's functions in
 *                   trace_path's order (kernels/integrator.cl), so that each lane draws the
 *                   megakernel's random numbers */

#define LANE(v, l) (((float *)&(v))[l])
#define ILANE(v, l) (((int *)&(v))[l])

typedef struct {
    floatN ox, oy, oz, dx, dy, dz, t;   /* rays, and each one's nearest hit so far (or t_max) */
    floatN b1, b2;                      /* a triangle hit's barycentric weights of v1 and v2 */
    intN prim, self, live;              /* hit (-1: none), the primitive left, still walking */
} Packet;

void set_lane(Packet *P, int l, float3 o, float3 d, float t_max, int self)
{
    LANE(P->ox, l) = o.x; LANE(P->oy, l) = o.y; LANE(P->oz, l) = o.z;
    LANE(P->dx, l) = d.x; LANE(P->dy, l) = d.y; LANE(P->dz, l) = d.z;
    LANE(P->t, l) = t_max;
    ILANE(P->self, l) = self;
    ILANE(P->live, l) = -1;
}

/* The lanes that enter child c of node n before their nearest hit, and where they enter. */
intN enter_child(const global BVHNode *n, int c, const Packet *P, floatN ix, floatN iy, floatN iz,
                 floatN *t_enter)
{
    floatN x0 = (((const global float *)&n->lo_x)[c] - P->ox) * ix, x1 = (((const global float *)&n->hi_x)[c] - P->ox) * ix;
    floatN y0 = (((const global float *)&n->lo_y)[c] - P->oy) * iy, y1 = (((const global float *)&n->hi_y)[c] - P->oy) * iy;
    floatN z0 = (((const global float *)&n->lo_z)[c] - P->oz) * iz, z1 = (((const global float *)&n->hi_z)[c] - P->oz) * iz;
    floatN te = fmax(fmax(fmin(x0, x1), fmin(y0, y1)), fmax(fmin(z0, z1), (floatN)(0.0f)));
    floatN tx = fmin(fmin(fmax(x0, x1), fmax(y0, y1)), fmin(fmax(z0, z1), P->t)) * BOX_EXIT_SCALE;
    *t_enter = te;
    return P->live & (te <= tx) & (te < P->t);
}

void hit_triangle(const global Triangle *tri, int id, Packet *P, intN lanes)
{
    float3 v0 = tri->v0.xyz, e1 = tri->v1.xyz - v0, e2 = tri->v2.xyz - v0;
    floatN px = P->dy * e2.z - P->dz * e2.y, py = P->dz * e2.x - P->dx * e2.z, pz = P->dx * e2.y - P->dy * e2.x;
    floatN det = e1.x * px + e1.y * py + e1.z * pz, inv = 1.0f / det;
    floatN sx = P->ox - v0.x, sy = P->oy - v0.y, sz = P->oz - v0.z;
    floatN u = (sx * px + sy * py + sz * pz) * inv;
    floatN qx = sy * e1.z - sz * e1.y, qy = sz * e1.x - sx * e1.z, qz = sx * e1.y - sy * e1.x;
    floatN v = (P->dx * qx + P->dy * qy + P->dz * qz) * inv;
    floatN t = (e2.x * qx + e2.y * qy + e2.z * qz) * inv;
    intN hit = lanes & (det != 0.0f) & (u >= 0.0f) & (v >= 0.0f) & (u + v <= 1.0f) & (t > 0.0f)
               & (t < P->t) & (P->self != id);
    P->t = select(P->t, t, hit);
    P->prim = select(P->prim, (intN)(id), hit);
    P->b1 = select(P->b1, u, hit);
    P->b2 = select(P->b2, v, hit);
}

void hit_sphere(Sphere s, int id, Packet *P, intN lanes)
{
    floatN fx = P->ox - s.x, fy = P->oy - s.y, fz = P->oz - s.z;
    floatN b = fx * P->dx + fy * P->dy + fz * P->dz;
    floatN disc = b * b - (fx * fx + fy * fy + fz * fz - s.w * s.w);
    floatN q = sqrt(fmax(disc, 0.0f));
    floatN t = select(-b + q, -b - q, -b - q > 0.0f);
    intN hit = lanes & (disc >= 0.0f) & (t > 0.0f) & (t < P->t);
    P->t = select(P->t, t, hit);
    P->prim = select(P->prim, (intN)(id), hit);
}

/* Walks the tree for the packet's live lanes (each lane's nearest hit, or with any_hit its
 * first); returns the nodes visited. */
int trace_packet(const SceneData *sc, Packet *P, int any_hit)
{
    floatN ix = 1.0f / P->dx, iy = 1.0f / P->dy, iz = 1.0f / P->dz;
    P->prim = (intN)(-1);
    int stack[BVH_STACK_SIZE * 2];   /* four pushes a node where the walk of one ray makes three */
    int top = 0, node = 0, visits = 0;
    while (node >= 0 && any(P->live)) {
        const global BVHNode *n = &sc->nodes[node];
        ++visits;
        float near[4];
        int inner[4], pushed = 0;
        for (int c = 0; c < 4; ++c) {
            floatN te;
            intN lanes = enter_child(n, c, P, ix, iy, iz, &te);
            if (!any(lanes))
                continue;
            int first = ((const global int *)&n->index)[c], count = ((const global int *)&n->count)[c];
            for (int j = first; j < first + count; ++j)
                hit_sphere(sc->spheres[j], j, P, lanes);
            for (int j = first; j < first - count; ++j)
                hit_triangle(&sc->triangles[j], sc->num_spheres + j, P, lanes);
            if (count == 0) {
                float nearest = INFINITY;
                for (int l = 0; l < LANES; ++l)
                    nearest = ILANE(lanes, l) ? fmin(nearest, LANE(te, l)) : nearest;
                /* insertion, farthest first, so that the nearest pops first */
                int k = pushed++;
                for (; k > 0 && near[k - 1] < nearest; --k) {
                    near[k] = near[k - 1];
                    inner[k] = inner[k - 1];
                }
                near[k] = nearest;
                inner[k] = first;
            }
        }
        if (any_hit)
            P->live &= P->prim < 0;
        for (int k = 0; k < pushed; ++k)
            stack[top++] = inner[k];
        node = top ? stack[--top] : -1;
    }
    return visits;
}

/* The pixel of lane l of tile k, or -1 past the image's whole tiles. */
int lane_pixel(const RenderParams *p, int k, int l)
{
    int tiles_x = p->width / TILE_W;
    if (k >= tiles_x * (p->height / TILE_H))
        return -1;
    return ((k / tiles_x) * TILE_H + l / TILE_W) * p->width + (k % tiles_x) * TILE_W + l % TILE_W;
}

kernel void trace_packets(SCENE_KERNEL_ARGS, const RenderParams p, const global float4 *rays, int which,
                          global int *hits, global int *visits)
{
    SceneData sc = SCENE_DATA(p.num_spheres);
    int k = get_global_id(0);
    if (lane_pixel(&p, k, 0) < 0)
        return;
    Packet P;
    P.live = (intN)(0);
    for (int l = 0; l < LANES; ++l) {
        int i = lane_pixel(&p, k, l);
        float4 o = rays[i * 6 + 2 * which], d = rays[i * 6 + 2 * which + 1];
        if (any(d.xyz != 0.0f))
            set_lane(&P, l, o.xyz, d.xyz, o.w, as_int(d.w));
    }
    intN rays_there = P.live;
    visits[k] = trace_packet(&sc, &P, which == 2);
    for (int l = 0; l < LANES; ++l) {
        int prim = ILANE(P.prim, l);
        hits[lane_pixel(&p, k, l)] = !ILANE(rays_there, l) ? -2 : which == 2 ? prim >= 0 : prim;
    }
}

kernel void render_packets(SCENE_KERNEL_ARGS, const RenderParams p, global float4 *sum)
{
    SceneData scene = SCENE_DATA(p.num_spheres);
    const SceneData *sc = &scene;
    int k = get_global_id(0);
    if (lane_pixel(&p, k, 0) < 0)
        return;
    float3 acc[LANES];
    for (int l = 0; l < LANES; ++l)
        acc[l] = (float3)(0.0f);
    for (uint sample = 0; sample < p.sample_count; ++sample) {
        Rng rng[LANES];
        float3 radiance[LANES], throughput[LANES], prev_x[LANES], prev_n[LANES], d[LANES], light[LANES];
        float pdf_prev[LANES];
        Packet P, Q;                      /* the paths' rays, and their shadow rays */
        P.live = (intN)(0);
        for (int l = 0; l < LANES; ++l) {
            int i = lane_pixel(&p, k, l), x = i % p.width, y = i / p.width;
            rng[l] = make_rng(x, y, p.sample_start + sample, p.seed);
            CameraRay ray = sample_camera_ray(&p, x, y, &rng[l]);
            d[l] = ray.d;
            prev_x[l] = ray.o;
            prev_n[l] = (float3)(0.0f);
            pdf_prev[l] = 0.0f;
            radiance[l] = (float3)(0.0f);
            throughput[l] = (float3)(1.0f);
            set_lane(&P, l, ray.o, ray.d, INFINITY, -1);
        }
        for (int depth = 1; any(P.live); ++depth) {
            trace_packet(sc, &P, 0);
            Q.live = (intN)(0);
            for (int l = 0; l < LANES; ++l) {
                if (!ILANE(P.live, l))
                    continue;
                ILANE(P.live, l) = 0;
                Hit hit = {LANE(P.t, l), ILANE(P.prim, l), LANE(P.b1, l), LANE(P.b2, l)};
                if (hit.prim < 0) {
                    float w = 1.0f;
                    if (pdf_prev[l] > 0.0f && p.env_pick > 0.0f)
                        w = mis_weight(pdf_prev[l], p.env_pick * pdf_environment(sc, &p, prev_n[l], d[l]));
                    radiance[l] += throughput[l] * lookup_environment(sc->env, &p, d[l]) * w;
                    continue;
                }
                float3 o = (float3)(LANE(P.ox, l), LANE(P.oy, l), LANE(P.oz, l));
                Surface s = surface_at(sc, &hit, o, d[l]);
                int flags = sc->materials[sc->prim_material[hit.prim]].flags;
                int front = dot(s.ng, d[l]) < 0.0f;
                if (!front) {
                    if (flags & MATERIAL_TWOSIDED)
                        turn_round(&s);
                    else if (!(flags & MATERIAL_TRANSMISSIVE))
                        continue;
                }
                MATERIAL_AT(m, sc, s, d[l]);
                if (front && any(m->emission.xyz > 0.0f)) {
                    float w = pdf_prev[l] > 0.0f
                        ? mis_weight(pdf_prev[l], pdf_light(sc, hit.prim, prev_x[l], prev_n[l], s.p)) : 1.0f;
                    radiance[l] += throughput[l] * m->emission.xyz * w;
                }
                if (depth >= p.max_depth)
                    continue;
                float3 wo = to_shading(&s, -d[l]);
                if (p.num_lights > 0 && !(m->flags & MATERIAL_DELTA)) {
                    LightSample ls = sample_light(sc, &p, s.p, s.ns, next_bits4(&rng[l]), &rng[l]);
                    float3 wi = to_shading(&s, ls.wi);
                    float3 f = ls.pdf > 0.0f && dot(ls.wi, s.ng) * wi.z > 0.0f ? eval_bsdf(m, wo, wi) : (float3)(0.0f);
                    if (any(f != 0.0f)) {
                        float w = (ls.flags & LIGHT_DELTA) ? 1.0f : mis_weight(ls.pdf, pdf_bsdf(m, wo, wi));
                        light[l] = throughput[l] * f * fabs(wi.z) * ls.le * (w / ls.pdf);
                        float3 so = offset_ray_origin(s.p, s.offset, s.ng, ls.wi), sd;
                        float t_max = shadow_ray(so, &ls, &sd);
                        set_lane(&Q, l, so, sd, t_max, hit.prim);
                    }
                }
                BSDFSample bs;
                bs.eta = 1.0f;
                if (!sample_bsdf(m, wo, next_uniform4(&rng[l]).xyz, &bs))
                    continue;
                float3 wi = from_shading(&s, bs.wi);
                if (dot(wi, s.ng) * bs.wi.z <= 0.0f)
                    continue;
                throughput[l] *= bs.weight;
                pdf_prev[l] = (bs.lobe & LOBE_DELTA) ? 0.0f : bs.pdf;
                prev_x[l] = s.p;
                prev_n[l] = s.ns;
                d[l] = wi;
                set_lane(&P, l, offset_ray_origin(s.p, s.offset, s.ng, wi), wi, INFINITY, hit.prim);
            }
            intN shadows = Q.live;
            if (any(shadows)) {
                trace_packet(sc, &Q, 1);
                for (int l = 0; l < LANES; ++l)
                    if (ILANE(shadows, l) && ILANE(Q.prim, l) < 0)
                        radiance[l] += light[l];
            }
        }
        for (int l = 0; l < LANES; ++l)
            if (all(isfinite(radiance[l])))
                acc[l] += radiance[l];
    }
    for (int l = 0; l < LANES; ++l)
        sum[lane_pixel(&p, k, l)] += (float4)(acc[l], (float)p.sample_count);
}
