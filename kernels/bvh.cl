/* Ray queries against the whole scene: the nearest hit through the BVH, over spheres and
 * triangles together. In a scene with alpha masks a hit the mask cuts out is no hit
 * (kernels/masks.cl). */

typedef struct {
    float t;
    int prim;     /* primitive index (types.h); -1: no hit */
    float b1;     /* a triangle hit's barycentric weights of v1 and v2 */
    float b2;
} Hit;

#define BOX_EXIT_SCALE 1.0000003576f

/* Entry distances of the ray into a 4-wide node's four boxes, INFINITY where it misses one or
 * enters past t_max. The exit distance is scaled up by 1 + 2 gamma(3), the rounding of its
 * computation (pbrt-v4 section 6.8.2), so that a ray grazing a thin box (a sliver triangle's) is
 * never missed. An empty slot's box lies at +inf and is never entered. */
float4 intersect_boxes(const global BVHNode *n, float3 o, float3 inv_d, float t_max)
{
    float4 x0 = (n->lo_x - o.x) * inv_d.x, x1 = (n->hi_x - o.x) * inv_d.x;
    float4 y0 = (n->lo_y - o.y) * inv_d.y, y1 = (n->hi_y - o.y) * inv_d.y;
    float4 z0 = (n->lo_z - o.z) * inv_d.z, z1 = (n->hi_z - o.z) * inv_d.z;
    float4 t_enter = fmax(fmax(fmin(x0, x1), fmin(y0, y1)), fmax(fmin(z0, z1), 0.0f));
    float4 t_exit = fmin(fmin(fmax(x0, x1), fmax(y0, y1)), fmax(z0, z1)) * BOX_EXIT_SCALE;
    t_exit = fmin(t_exit, t_max);
    return select((float4)(INFINITY), t_enter, t_enter <= t_exit);
}

void intersect_spheres(const SceneData *sc, int first, int count, float3 o, float3 d, Hit *hit)
{
    for (int i = first; i < first + count; ++i) {
#ifdef ALPHA_MASKS
        /* the ray crosses a sphere's surface twice: where the mask cuts the nearer crossing out,
           the farther one may be met */
        float2 crossings = sphere_crossings(sc->spheres[i], o, d);
        float t = INFINITY;
        for (int k = 0; k < 2; ++k) {
            float tk = k == 0 ? crossings.x : crossings.y;
            if (tk > 0.0f && tk < hit->t && !masked_out(sc, i, (float2)(0.0f), o + tk * d, d)) {
                t = tk;
                break;
            }
        }
#else
        float t = intersect_sphere(sc->spheres[i], o, d, hit->t);
#endif
        if (t < hit->t) {
            hit->t = t;
            hit->prim = i;
        }
    }
}

/* `self`: the primitive the ray leaves (or -1), which a plane cannot meet again: skipped. */
void intersect_triangles(const SceneData *sc, int first, int count, float3 o, float3 d, int self,
                         Hit *hit)
{
    float3 row_x, row_y, row_z;
    triangle_shear(d, &row_x, &row_y, &row_z);
    for (int i = first; i < first + count; ++i) {
        if (sc->num_spheres + i == self)
            continue;
        float b1, b2;
        float t = intersect_triangle(&sc->triangles[i], o, row_x, row_y, row_z, hit->t, &b1, &b2);
#ifdef ALPHA_MASKS
        if (t < hit->t && masked_out(sc, sc->num_spheres + i, (float2)(b1, b2), o + t * d, d))
            continue;
#endif
        if (t < hit->t) {
            hit->t = t;
            hit->prim = sc->num_spheres + i;
            hit->b1 = b1;
            hit->b2 = b2;
        }
    }
}

/* Tests the primitives of a node's leaves that the ray enters (t < INFINITY); returns t with the
 * leaves' slots set to INFINITY, leaving the inner children's. NO_TRIANGLES (a build option for
 * scenes of spheres only) leaves the triangle code out. Sphere leaves are short, so the
 * four slots are tested unrolled; with triangles, one copy of the (inlined) primitive tests in
 * a loop over the leaves' bits keeps the kernel's registers down (the teapot's NEE kernel ran
 * 26 % slower on the H100 with four copies, the sphere scenes 6-8 % faster). */
float4 intersect_leaves(const SceneData *sc, float4 t, int4 count, int4 index, float3 o, float3 d,
                        int self, Hit *hit)
{
    int4 leaf = (t < INFINITY) & (count != 0);
#ifdef NO_TRIANGLES
    if (leaf.x) intersect_spheres(sc, index.x, count.x, o, d, hit);
    if (leaf.y) intersect_spheres(sc, index.y, count.y, o, d, hit);
    if (leaf.z) intersect_spheres(sc, index.z, count.z, o, d, hit);
    if (leaf.w) intersect_spheres(sc, index.w, count.w, o, d, hit);
#else
    uint leaves = (leaf.x & 1) | (leaf.y & 2) | (leaf.z & 4) | (leaf.w & 8);
    while (leaves) {
        uint k = 31 - clz(leaves & (0u - leaves));
        leaves &= leaves - 1;
        int c = k == 0 ? count.x : k == 1 ? count.y : k == 2 ? count.z : count.w;
        int i = k == 0 ? index.x : k == 1 ? index.y : k == 2 ? index.z : index.w;
        if (c > 0)
            intersect_spheres(sc, i, c, o, d, hit);
        else
            intersect_triangles(sc, i, -c, o, d, self, hit);
    }
#endif
    return select(t, (float4)(INFINITY), leaf);
}

/* app/bvh.py keeps the binary tree at most 30 levels deep, so the 4-wide one at most 15, and
 * traversal pushes at most three nodes per level: 48 entries. A scene's program is built with
 * the size its own tree needs (app/features.py: stack_size). */
#ifndef BVH_STACK_SIZE
#define BVH_STACK_SIZE 48
#endif

/* The hit along o + t d, t in (0, t_max): the nearest one, or with any_hit (a constant at each
 * call, so the compiler builds two traversals) the first one found, which is all a shadow ray
 * needs to know. A node's leaves are tested at once; its inner children are visited
 * nearer-first, the others pushed farther-first. The stack holds node indices only (small
 * private memory keeps GPU occupancy up); a popped node's boxes are tested against the nearest
 * hit found meanwhile. Rays leaving a surface start at an offset origin (kernels/spawn.cl) and
 * skip the triangle they leave (`self`), so that a neighbour met at t ~ 0 (in a concave corner)
 * is met, not lost to a bound on t's rounding that only the triangle left behind needs. */
/* Orders two (distance, node) pairs nearer-first; selects, not branches, so everything stays in
 * registers. */
#define ORDER(ta, ia, tb, ib) {                                 \
        int swap = tb < ta;                                      \
        float t_ = swap ? tb : ta; tb = swap ? ta : tb; ta = t_; \
        int i_ = swap ? ib : ia; ib = swap ? ia : ib; ia = i_;   \
    }

#ifdef FLAT_SPHERES
/* A scene of a few primitives (app/features.py: FLAT_MAX) is not traversed: each ray tests them
 * all, FLAT_SPHERES spheres and FLAT_TRIANGLES triangles, constants that let the loops unroll. */
Hit trace_ray(const SceneData *sc, float3 o, float3 d, float t_max, int self, const int any_hit)
{
    Hit hit = {t_max, -1, 0.0f, 0.0f};
    intersect_spheres(sc, 0, FLAT_SPHERES, o, d, &hit);
#ifndef NO_TRIANGLES
    intersect_triangles(sc, 0, FLAT_TRIANGLES, o, d, self, &hit);
#endif
    return hit;
}
#else
Hit trace_ray(const SceneData *sc, float3 o, float3 d, float t_max, int self, const int any_hit)
{
    Hit hit = {t_max, -1, 0.0f, 0.0f};
    float3 inv_d = 1.0f / d;
    int stack[BVH_STACK_SIZE];
    int top = 0;
    int node = 0;
    for (;;) {
        const global BVHNode *n = &sc->nodes[node];
        float4 t = intersect_boxes(n, o, inv_d, hit.t);
        int4 index = n->index;
        t = intersect_leaves(sc, t, n->count, index, o, d, self, &hit);
        if (any_hit && hit.prim >= 0)
            return hit;
        /* the inner children still in front of the nearest hit (a leaf hit may have moved it in
         * front of some), sorted by a five-comparator network: the nearest is visited next, the
         * others pushed farthest first so that they pop nearest first */
        float t0 = t.x, t1 = t.y, t2 = t.z, t3 = t.w;
        int i0 = index.x, i1 = index.y, i2 = index.z, i3 = index.w;
        ORDER(t0, i0, t1, i1);
        ORDER(t2, i2, t3, i3);
        ORDER(t0, i0, t2, i2);
        ORDER(t1, i1, t3, i3);
        ORDER(t1, i1, t2, i2);
        if (t3 < hit.t) stack[top++] = i3;
        if (t2 < hit.t) stack[top++] = i2;
        if (t1 < hit.t) stack[top++] = i1;
        if (t0 < hit.t) {
            node = i0;
            continue;
        }
        if (top == 0)
            return hit;
        node = stack[--top];
    }
}
#endif

/* The nearest hit along o + t d, t in (0, t_max), skipping triangle `self` (the primitive the
 * ray leaves, or -1). */
Hit intersect_scene(const SceneData *sc, float3 o, float3 d, float t_max, int self)
{
    return trace_ray(sc, o, d, t_max, self, 0);
}

/* Whether anything but `self` lies on o + t d for t in (0, t_max). */
int occluded(const SceneData *sc, float3 o, float3 d, float t_max, int self)
{
    return trace_ray(sc, o, d, t_max, self, 1).prim >= 0;
}

/* What a path needs of the surface it hit. */
typedef struct {
    float3 p;        /* the point */
    float3 ng;       /* unit geometric normal, on the front side */
    float3 ns;       /* unit shading normal, in ng's hemisphere */
    float offset;    /* how far rays leaving p start from it along ng (kernels/spawn.cl) */
    int prim;        /* the primitive hit */
#ifdef TEXTURES
    float2 b;        /* a triangle's barycentric weights of v1 and v2, from which surface_uv
                        finds its texture coordinates when a texture needs them */
#endif
#if defined(NORMAL_MAPS) || defined(MEDIA)
    float side;              /* 1; -1 once turned round to a two-sided material's back */
#endif
#ifdef NORMAL_MAPS
    float3 ns_unperturbed;   /* the shading normal before a normal or bump map (normal_maps.cl) */
    float terminator;        /* the shadowing term's alpha^2 (0: no perturbation) */
#endif
#ifdef ANISOTROPIC
    float3 ts;               /* the shading frame's unit tangent (frame.cl: complete_frame) */
#endif
} Surface;

Surface surface_at(const SceneData *sc, const Hit *hit, float3 o, float3 d)
{
    Surface s;
    float3 error;
    s.prim = hit->prim;
#ifndef NO_TRIANGLES
    if (hit->prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[hit->prim - sc->num_spheres];
        triangle_surface(tri, sc->normals, hit->b1, hit->b2, &s.p, &error, &s.ng, &s.ns);
        s.offset = error_offset(s.ng, error);
#ifdef TEXTURES
        s.b = (float2)(hit->b1, hit->b2);
#endif
#if defined(NORMAL_MAPS) || defined(MEDIA)
        s.side = 1.0f;
#endif
        return s;
    }
#endif
    sphere_surface(sc->spheres[hit->prim], o, d, hit->t, &s.p, &error, &s.ng);
    s.ns = s.ng;
    s.offset = error_offset(s.ng, error);
#ifdef TEXTURES
    s.b = (float2)(0.0f);
#endif
#if defined(NORMAL_MAPS) || defined(MEDIA)
    s.side = 1.0f;
#endif
    return s;
}

/* The back of a two-sided material: its normals turned round (Mitsuba 3's `twosided` mirrors
 * the shading frame's z, keeping its tangents). */
void turn_round(Surface *s)
{
    s->ng = -s->ng;
    s->ns = -s->ns;
#if defined(NORMAL_MAPS) || defined(MEDIA)
    s->side = -1.0f;
#endif
}

/* The texture coordinates of point p on primitive prim, a triangle's barycentric weights b (a
 * program for a scene with textures has them). */
float2 surface_uv(const SceneData *sc, int prim, float2 b, float3 p)
{
#ifndef NO_TRIANGLES
    if (prim >= sc->num_spheres)
        return triangle_uv(&sc->triangles[prim - sc->num_spheres], sc->uvs, b.x, b.y);
#endif
    return sphere_uv(sc->spheres[prim], p);
}
