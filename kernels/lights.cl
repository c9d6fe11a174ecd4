/* The light interface for next-event estimation. Every light is one entry of one light table,
 * chosen in proportion to its power through an alias table (app/lights/table.py); then its type
 * (kernels/lights/<name>.cl) samples a direction towards it. Each type provides
 *
 *   sample_X_light(sc, p, l, x, n, u, &ls)   a direction wi from point x (shading normal n)
 *                                            towards light l, from two uniforms: its density
 *                                            per solid angle (1 for a delta light), the point it
 *                                            aims at, LIGHT_* flags, and the radiance arriving
 *                                            at x along it (for a delta light, what it delivers:
 *                                            intensity / r^2, or irradiance); returns 0 when none
 *
 * and app/lights/registry.py generates the dispatch on the type tag (LIGHT_<NAME>), so that the
 * integrator never names a light type. The radiance comes with the sample, sparing a second
 * dispatch on the type after the BSDF's evaluation (docs/notes/performance-2026-11.md, 2026-11-24: lights as
 * interfaces). Area
 * lights and the environment also give the density with which they would have sampled a
 * direction that a path found by itself (pdf_light, pdf_environment), for multiple importance
 * sampling; delta lights cannot be found so, and carry no MIS weight. */

#define LIGHT_DELTA 1          /* a delta light: no path finds it, no MIS weight */
#define LIGHT_AT_INFINITY 2    /* the shadow ray runs to infinity, not to the sample's point */

typedef struct {
    float3 wi;       /* unit direction from the shading point towards the light */
    float3 y;        /* the point on the light the shadow ray ends at (unless at infinity) */
    float3 le;       /* the radiance arriving along wi */
    float pdf;       /* its density per solid angle, the light's choice included; for a delta
                        light the choice probability alone */
    int light;       /* its entry of the light table */
    int flags;       /* LIGHT_* */
} LightSample;

#ifdef BDPT
/* Light leaving a light, the first vertex of a light subpath (kernels/bdpt.cl): each type that
 * can start one provides emit_X_light(sc, l, u, &e) and the density of its directions,
 * dispatched by emit_light_of_type and pdf_emission_of_type (app/lights/registry.py: EMITTERS). */
typedef struct {
    float3 p;        /* the point it leaves */
    float3 n;        /* an area light's unit normal on the side it leaves (0: a point) */
    float3 d;        /* the unit direction it leaves in */
    float3 le;       /* radiance (area lights) or intensity (point and spot lights) along d */
    float pdf_pos;   /* density of p per area (1 for a point, whose position is a delta) */
    float pdf_dir;   /* density of d per solid angle */
    float offset;    /* how far rays leaving p start from it along n (kernels/spawn.cl) */
    int prim;        /* an area light's primitive, else -1 */
    int delta;       /* a point, spot or directional light: no path finds it */
    int at_infinity; /* the environment or a directional light (leave_world_disk) */
} LightEmission;

int emit_light_of_type(const SceneData *sc, const RenderParams *p, const global Light *l, float4 u,
                       LightEmission *e);
float pdf_emission_of_type(const SceneData *sc, const RenderParams *p, const global Light *l, float3 n, float3 w);

/* Where light from infinitely far away, travelling in direction d, starts a light subpath: a
 * point uniform on the disk of the scene's bounding sphere's radius across d, beyond the sphere
 * on the side it comes from, so that the parallel rays from the disk cover the scene (pbrt-v4's
 * SampleLe of its infinite and distant lights). Its density per area is 1 / (pi r^2), the
 * density per area of the subpath's first hit times the cosine there (kernels/bdpt.cl). */
void leave_world_disk(const RenderParams *p, float3 d, float2 u, LightEmission *e)
{
    float r = p->world.w;
    float2 c = r * sample_concentric_disk(u);
    e->p = p->world.xyz + to_world((float3)(c, -r), d);
    e->d = d;
    e->n = (float3)(0.0f);
    e->pdf_pos = 1.0f / (PI_F * r * r);
    e->offset = 0.0f;
    e->prim = -1;
    e->at_infinity = 1;
}
#endif

/* Walker's alias method: a bin chosen uniformly, then kept or replaced by its alias, picks a
 * light in proportion to its power. The bin comes from all 32 bits of one hash word, as
 * floor(bin_bits * count / 2^32) (each bin's probability is 1/count to within count / 2^32
 * relative), and the keep test from all 32 bits of another, against the threshold the host
 * stored (app/lights/table.py keep_threshold). Drawing both from one float, as before, left the
 * keep test 24 - log2(count) bits, which skewed the choice by up to 2x at 2^17 lights. */
int pick_light(const global Light *lights, int count, uint bin_bits, uint keep_bits)
{
    int i = (int)mul_hi(bin_bits, (uint)count);
    return keep_bits < lights[i].keep ? i : lights[i].alias;
}

/* The sample of a delta light at `position`: the one direction towards it from x (none from
 * the position itself), and the squared distance *r2. */
int aim_at_position(float3 position, float3 x, LightSample *ls, float *r2)
{
    float3 v = position - x;
    *r2 = dot(v, v);
    if (!(*r2 > 0.0f))
        return 0;
    ls->y = position;
    ls->wi = v * rsqrt(*r2);
    ls->pdf = 1.0f;
    ls->flags = LIGHT_DELTA;
    return 1;
}

/* A world direction w in the own space of a light whose rotation to the world is the unit
 * quaternion q = (x, y, z, w) (app/lights/light.py: frame_quaternion): w turned by q's
 * conjugate, v + 2 u x (u x v + s v) with u = -q.xyz and s = q.w. */
float3 to_light_space(float4 q, float3 w)
{
    float3 u = -q.xyz;
    return w + 2.0f * cross(u, cross(u, w) + q.w * w);
}

/* aim_at_position for a light with a frame of its own, its rotation to the world the unit
 * quaternion q: also *w, the direction from the light towards x in the light's space, by which
 * an image light (goniometric, projection) looks up its image. */
int aim_from_frame(float3 position, float4 q, float3 x, LightSample *ls, float *r2, float3 *w)
{
    if (!aim_at_position(position, x, ls, r2))
        return 0;
    *w = to_light_space(q, -ls->wi);
    return 1;
}

/* The generated dispatch (app/lights/registry.py), defined after the types' files. */
int sample_light_of_type(const SceneData *sc, const RenderParams *p, const global Light *l,
                         float3 x, float3 n, float2 u, LightSample *ls);

#ifdef LIGHT_TREE
int pick_from_tree(const SceneData *sc, const global Light *root, float3 x, float3 n, Rng *rng,
                   float *pick);
float tree_pick_probability(const SceneData *sc, int leaf, float3 x, float3 n);
#endif

/* Draws a light and a direction towards it from point x of shading normal n, from four hash
 * words: the light from r.w and r.x (and, through a light tree, from more words of the rng),
 * the direction from r.y and r.z. A sample of pdf 0 is none. */
LightSample sample_light(const SceneData *sc, const RenderParams *p, float3 x, float3 n, uint4 r, Rng *rng)
{
    LightSample ls;
    ls.light = pick_light(sc->lights, p->num_lights, r.w, r.x);
    ls.flags = 0;
    ls.pdf = 0.0f;
    const global Light *l = &sc->lights[ls.light];
    float pick = l->pick;
#ifdef LIGHT_TREE
    if (l->type == LIGHT_TREE_ROOT) {
        ls.light = pick_from_tree(sc, l, x, n, rng, &pick);
        if (ls.light < 0)
            return ls;
        l = &sc->lights[ls.light];
    }
#endif
    if (sample_light_of_type(sc, p, l, x, n, to_uniform4(r).yz, &ls))
        ls.pdf *= pick;
    else
        ls.pdf = 0.0f;
    return ls;
}
