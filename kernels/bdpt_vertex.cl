/* A vertex of a bidirectional path tracer's subpath (kernels/bdpt.cl): how light scatters there
 * and with what density, and the weights of multiple importance sampling computed from the
 * densities vertices store (Veach 1997, section 10.2; pbrt-v4's BDPTIntegrator MISWeight). */

#define BDPT_CAMERA_VERTICES (BDPT + 1)
#define BDPT_LIGHT_VERTICES BDPT

/* One vertex of a subpath. The camera and a light are vertices of their own: s.p is their
 * point and s.ng an area light's normal (0 for the camera and a point). A scattering inside a
 * medium is a vertex with no surface: s.ng and s.ns 0, s.prim -1. A light at infinity (the
 * environment, a directional light) is a vertex at_infinity: a direction rather than a point,
 * its densities per solid angle (pbrt-v4's infinite light vertices): a light subpath's first,
 * s.p the point on the scene's disk it left (kernels/lights.cl: leave_world_disk), or a camera
 * subpath's last, where it escaped, wo back along the escaping ray. */
typedef struct {
    Surface s;            /* a surface vertex's surface, its shading frame complete, a perturbed
                             normal unturned (seen_from turns it) */
#ifdef TEXTURES
    Material m;           /* its material with the textures looked up there */
#else
    const global Material *m;
#endif
    float3 wo;            /* unit direction towards the vertex before it on its subpath */
    float3 beta;          /* the subpath's throughput up to it */
    float pdf_fwd;        /* density per area of drawing it along its own subpath */
    float pdf_rev;        /* density per area of drawing it from the other end */
    int delta;            /* its sampled lobe was a delta */
    int connectible;      /* a surface that scatters light into more than a delta lobe */
    int emits;            /* a surface that emits towards wo, or the environment */
    int at_infinity;      /* a light at infinity (above) */
    float mis_sum;        /* the MIS sum of the vertices up to it that no connection changes (sum_mis_ratios) */
#ifdef MEDIA
    int medium;           /* the medium around it: a medium vertex's own, the camera's or a light's,
                             or the one a surface vertex was reached through (-1: none) */
    int in_medium;        /* a scattering inside that medium, by its phase function */
#endif
} Vertex;

#ifdef TEXTURES
#define VERTEX_MATERIAL(v) ((MaterialRef)&(v)->m)
#else
#define VERTEX_MATERIAL(v) ((v)->m)
#endif

/* A density per solid angle at `from` as a density per area at `to`, whose geometric normal is
 * n (0: a point, no cosine): pbrt's Vertex::ConvertDensity. */
float convert_density(float pdf, float3 from, float3 to, float3 n)
{
    float3 w = to - from;
    float d2 = dot(w, w);
    if (!(d2 > 0.0f))
        return 0.0f;
    float c = any(n != 0.0f) ? fabs(dot(n, w)) * rsqrt(d2) : 1.0f;
    return pdf * c / d2;
}

/* A density per solid angle at `from` towards vertex v as v's density: per area
 * (convert_density), or for a vertex at infinity, a direction, unchanged (pbrt's
 * Vertex::ConvertDensity). */
float density_at(float pdf, float3 from, const Vertex *v)
{
    return v->at_infinity ? pdf : convert_density(pdf, from, v->s.p, v->s.ng);
}

/* The density per area with which light from infinity, travelling along d, reaches vertex v:
 * its disk's 1 / (pi r^2) (kernels/lights.cl: leave_world_disk) times the cosine at v's surface
 * (none inside a medium; pbrt's Vertex::PdfLight of an infinite light). */
float density_from_infinity(const RenderParams *p, float3 d, const Vertex *v)
{
    float c = any(v->s.ng != 0.0f) ? fabs(dot(v->s.ng, d)) : 1.0f;
    return c / (PI_F * p->world.w * p->world.w);
}

/* Whether vertex v is a scattering inside a medium. */
int in_medium(const Vertex *v)
{
#ifdef MEDIA
    return v->in_medium;
#else
    return 0;
#endif
}

/* The phase function's mean cosine at medium vertex v. */
float phase_g(const SceneData *sc, const Vertex *v)
{
#ifdef MEDIA
    return sc->media[v->medium].sigma_s.w;
#else
    return 0.0f;
#endif
}

/* The medium a ray leaving vertex v in direction w crosses first: beyond v's surface on w's
 * side, or where v lies on no primitive (a medium vertex, the camera, a point light) the
 * medium around it. -1 without media. */
int medium_towards(const SceneData *sc, const Vertex *v, float3 w)
{
#ifdef MEDIA
    return v->s.prim < 0 ? v->medium : medium_after(sc, &v->s, w, v->medium);
#else
    return -1;
#endif
}

/* Surface vertex v's surface as seen from `to`, the direction towards the camera's side: with
 * Mitsuba's normal maps, its perturbed normal turned as the path tracer turns it for that side
 * (kernels/normal_maps.cl: turns_perturbed_normal), in `turned`, or else v's own. A vertex
 * keeps the normal unturned, since a light subpath's vertex learns the camera's side only when
 * it is joined or scattered on. So both subpaths evaluate the path tracer's BSDF, which is not
 * reciprocal, in the frame the camera's side chooses, where Mitsuba 3's particle tracer turns
 * the normal by the side light arrives from. SEEN_FROM declares `s`, that surface (v's own
 * without normal maps). */
#ifdef NORMAL_MAPS
const Surface *seen_from(const SceneData *sc, const Vertex *v, float3 to, Surface *turned)
{
    if (!turns_perturbed_normal(&v->s, to))
        return &v->s;
    *turned = v->s;
    turn_perturbed_normal(turned);
    complete_frame(sc, turned);
    return turned;
}
#define SEEN_FROM(s, sc, v, to) Surface s##_turned; const Surface *s = seen_from(sc, v, to, &s##_turned)
#else
#define SEEN_FROM(s, sc, v, to) const Surface *s = &(v)->s
#endif

/* Veach's correction of the adjoint BSDF for shading normals (thesis, eq. 5.19; pbrt-v3's
 * CorrectShadingNormal): importance arriving along wo and leaving along wi, at surface s. */
float correct_shading_normal(const Surface *s, float3 wo, float3 wi)
{
    float den = fabs(dot(wo, s->ng)) * fabs(dot(wi, s->ns));
    return den > 0.0f ? fabs(dot(wo, s->ns)) * fabs(dot(wi, s->ng)) / den : 0.0f;
}

/* Whether the path tracer carries light through surface s (its material transmitting or not)
 * leaving along world direction `to`, b in s's shading frame: where s is opaque, the shading
 * and geometric normals agree on the side towards the camera, which the path tracer reaches
 * from its front alone and where the BSDF is 0 below its frame; a transmitting BSDF reads such
 * a `to` as the other side, as the path tracer's does. The side light comes from is the shading
 * frame's alone, as the path tracer's (kernels/integrator.cl), but for Mitsuba's normal maps
 * (PERTURBED_SIDES_AGREE). */
int carries_light(const Surface *s, int transmitting, float3 to, float3 b)
{
    return transmitting || dot(to, s->ng) * b.z > 0.0f;
}

/* The BSDF of surface vertex v for light arriving along world direction `from` and leaving
 * along `to` (radiance flows from `from` to `to`), without the cosine, with the shading normal
 * `to` sees (seen_from); 0 where the path tracer carries no such light (carries_light). A perturbed normal's shadowing of `from`, the
 * side light comes from, as the path tracer weighs it (kernels/normal_maps.cl:
 * shadow_terminator), so that both estimate one image. A medium vertex's phase function, which
 * is symmetric. */
float3 eval_scattering(const SceneData *sc, const Vertex *v, float3 from, float3 to)
{
    if (in_medium(v))
        return (float3)(eval_hg(phase_g(sc, v), to, from));
    SEEN_FROM(s, sc, v, to);
    float3 a = to_shading(s, from), b = to_shading(s, to);
    if (!carries_light(s, VERTEX_MATERIAL(v)->flags & MATERIAL_TRANSMISSIVE, to, b)
        || !PERTURBED_SIDES_AGREE(s, from, a.z))
        return (float3)(0.0f);
    float3 f = eval_bsdf(VERTEX_MATERIAL(v), b, a);
#ifdef NORMAL_MAPS
    f *= shadow_terminator(s, from);
#endif
    return f;
}

/* The cosine that goes with eval_scattering(v, from, to) where vertex v is joined to another
 * along `to`: |cos from| with the shading normal `to` sees, or where importance flows (v on a
 * light subpath, joined to a camera vertex or the lens) the adjoint's, Veach's correction times
 * |cos to|; 1 inside a medium, whose phase function has no cosine. */
float joined_cos(const SceneData *sc, const Vertex *v, float3 from, float3 to, const int importance)
{
    if (in_medium(v))
        return 1.0f;
    SEEN_FROM(s, sc, v, to);
    return importance ? correct_shading_normal(s, from, to) * fabs(dot(to, s->ns)) : fabs(dot(from, s->ns));
}

/* The probability with which a light subpath scatters at surface s in the frame of its perturbed
 * normal turned (turn_perturbed_normal) or, `turned` 0, unturned: it draws the direction
 * towards the camera's side before it knows whether the path tracer's BSDF turns the normal for
 * that direction, so it draws the frame first, turned with probability (1 - m.n) / 2, and keeps
 * the direction only where that frame is the one the direction sees (kernels/bdpt_subpaths.cl:
 * extend_subpath). Any probability in (0, 1) reaches every direction the BSDF scatters into;
 * this one grows with the tilt, 0 where nothing turns, so that an untilted normal wastes no
 * subpath. */
#ifdef NORMAL_MAPS
float frame_probability(const Surface *s, int turned)
{
    float p_turn = s->terminator > 0.0f ? fmax(0.0f, 0.5f * (1.0f - dot(s->ns, s->ns_unperturbed))) : 0.0f;
    return turned ? p_turn : 1.0f - p_turn;
}
#endif

/* The density per solid angle with which vertex v, reached along `wo`, samples `wi`: by the
 * camera subpath's sampling (wo towards the camera's side) or, with importance, the light
 * subpath's (wi towards the camera's side), times the probability of the frame it drew
 * (frame_probability). */
float pdf_scattering(const SceneData *sc, const Vertex *v, float3 wo, float3 wi, const int importance)
{
    if (in_medium(v))
        return eval_hg(phase_g(sc, v), wo, wi);
    SEEN_FROM(s, sc, v, importance ? wi : wo);
    float pdf = pdf_bsdf(VERTEX_MATERIAL(v), to_shading(s, wo), to_shading(s, wi));
#ifdef NORMAL_MAPS
    if (importance)
        pdf *= frame_probability(&v->s, s != &v->s);     /* s turned, or v's own */
#endif
    return pdf;
}

/* A squared ratio of densities, or a product of them, that overflows is taken as the largest
 * float rather than infinity: a vertex a hair from the one before has an area density of 1e10
 * and more, and an overflow's infinity beside an underflow's 0 gave a product of inf * 0, a NaN
 * sample (Bitterli's coffee with BDPT: 4 in 2.1 million). Below the overflow every value is
 * unchanged, so a path's weights still sum to 1 wherever the squares fit in a float (densities'
 * ratios up to 1e19). */
#define MIS_RATIO_MAX FLT_MAX

/* The ratio of two strategies' densities as pbrt's MISWeight takes it, a delta's 0 read as 1,
 * squared for the power heuristic, at most MIS_RATIO_MAX. */
float density_ratio2(float rev, float fwd)
{
    float r = (rev != 0.0f ? rev : 1.0f) / (fwd != 0.0f ? fwd : 1.0f);
    return fmin(r * r, MIS_RATIO_MAX);
}

/* A product of two of the weights' terms, at most MIS_RATIO_MAX. */
float mis_product(float a, float b)
{
    return fmin(a * b, MIS_RATIO_MAX);
}

/* The power heuristic's weight of strategy (s, t) for the path made of light vertices
 * lt[0, s) and camera vertices cam[0, t) (pbrt-v4's BDPTIntegrator MISWeight with beta = 2):
 * the other strategies' densities relative to this one's, as products of the ratios of reverse
 * to forward densities along each subpath. The connection changes four reverse densities, of
 * camera vertices t - 1 and t - 2 and light vertices s - 1 and s - 2, given in rev (x, y, z, w);
 * the connected vertices count as non-delta. For s = 1 the light vertex is the one sampled
 * from camera vertex t - 1, not lt[0]: its forward density is origin_pdf. light_delta: the
 * light's position is a delta (a point or spot), which no camera subpath hits. The terms of
 * the vertices before those two are the subpaths' mis_sum (sum_mis_ratios), times the two
 * ratios the connection gives: the weight reads four vertices, not every vertex of both
 * subpaths as pbrt's loop does (on a GPU the subpaths live in local memory). */
float bdpt_mis_weight(const Vertex *lt, int s, const Vertex *cam, int t, float4 rev, float origin_pdf,
                      int light_delta)
{
    if (s + t == 2)
        return 1.0f;
    float sum = 0.0f;
    if (t > 1) {
        float r = density_ratio2(rev.x, cam[t - 1].pdf_fwd);
        if (!cam[t - 2].delta)
            sum += r;
        if (t > 2) {
            r = mis_product(r, density_ratio2(rev.y, cam[t - 2].pdf_fwd));
            if (!cam[t - 2].delta && !cam[t - 3].delta)
                sum += r;
            if (t > 3)
                sum += mis_product(r, cam[t - 3].mis_sum);
        }
    }
    if (s > 0) {
        float r = density_ratio2(rev.z, s == 1 ? origin_pdf : lt[s - 1].pdf_fwd);
        if (!(s > 1 ? lt[s - 2].delta : light_delta))
            sum += r;
        if (s > 1) {
            r = mis_product(r, density_ratio2(rev.w, lt[s - 2].pdf_fwd));
            if (!lt[s - 2].delta && !(s > 2 ? lt[s - 3].delta : light_delta))
                sum += r;
            if (s > 2)
                sum += mis_product(r, lt[s - 3].mis_sum);
        }
    }
    return 1.0f / (1.0f + sum);
}

/* Each vertex k of a traced subpath of n vertices gets the part of bdpt_mis_weight's sum that
 * no connection changes: Q(k), the sum over the vertices i <= k that count (neither i nor the
 * vertex before it a delta) of the products of the ratios of reverse to forward density of
 * vertices i to k, by the recurrence Q(k) = ratio(k) (Q(k - 1) + [k counts]), as the recursive
 * weights of van Antwerpen (2011) and Georgiev et al.'s vertex connection and merging (2012)
 * accumulate theirs. first: the first vertex that counts (1 on a camera subpath, whose vertex 0
 * is the lens; 0 on a light subpath); delta_origin: whether the position before vertex 0 is a
 * delta (a light subpath's point or spot light). */
void sum_mis_ratios(Vertex *path, int n, int first, int delta_origin)
{
    float q = 0.0f;
    for (int k = first; k < n; ++k) {
        int counts = !path[k].delta && !(k > 0 ? path[k - 1].delta : delta_origin);
        q = mis_product(density_ratio2(path[k].pdf_rev, path[k].pdf_fwd), q + (counts ? 1.0f : 0.0f));
        path[k].mis_sum = q;
    }
}
