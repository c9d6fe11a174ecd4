/* Ray queries against the whole scene: the nearest hit through the BVH, over spheres and
 * triangles together. In a scene with alpha masks a hit the mask cuts out is no hit
 * (kernels/masks.cl). A scene with instances (INSTANCES) has a two-level BVH: a tree over its
 * instances' boxes, whose leaves hold instances, each a tree over an object's primitives, which
 * the ray enters turned into the object's space (app/scene/instances.py). */

typedef struct {
    float t;
    int prim;     /* primitive index (types.h); -1: no hit */
    float b1;     /* a triangle hit's barycentric weights of v1 and v2 */
    float b2;
#ifdef INSTANCES
    int instance; /* the instance whose primitive it is */
#endif
} Hit;

/* A primitive where it is drawn: with instances, the pair (primitive, instance), since an
 * object's primitives are drawn by many; the surface a ray leaves is one (PrimId self). */
#ifdef INSTANCES
typedef int2 PrimId;
#define NO_PRIM ((int2)(-1))
#define HIT_ID(h) ((int2)((h).prim, (h).instance))
#define SURFACE_ID(s) ((int2)((s).prim, (s).instance))
#define IS_SELF(self, prim, instance) ((self).x == (prim) && (self).y == (instance))
#define SET_INSTANCE(hit, i) ((hit)->instance = (i))
#define PRIM_ID_PAIR(id) (id)
#define PRIM_ID_OF_PAIR(v) (v)
#else
typedef int PrimId;
#define NO_PRIM (-1)
#define HIT_ID(h) ((h).prim)
#define SURFACE_ID(s) ((s).prim)
#define IS_SELF(self, prim, instance) ((self) == (prim))
#define SET_INSTANCE(hit, i)
#define PRIM_ID_PAIR(id) ((int2)((id), -1))
#define PRIM_ID_OF_PAIR(v) ((v).x)
#endif
/* Whether a hit's primitive is an instance's: always in a scene's program with INSTANCES, whose
 * tree holds instances alone; in a GENERIC program, where the scene has them (walk_world). */
#ifdef GENERIC
#define INSTANCED(instance) ((instance) >= 0)
#else
#define INSTANCED(instance) 1
#endif

#define BOX_EXIT_SCALE 1.0000003576f

/* Entry distances of the ray into a 4-wide node's four boxes, INFINITY where it misses one or
 * enters past t_max. A plane's distance is plane * inv_d - o * inv_d, one fused multiply-add
 * (as Embree's). The rounding of o * inv_d (the same at every node of a walk, so the compiler
 * may compute it once) moves the near planes nearer and the far ones farther by two ulps of it,
 * and the exit distance is scaled up by 1 + 2 gamma(3), the rounding of the rest (pbrt-v4
 * section 6.8.2), so that a ray grazing a thin box (a sliver triangle's) is never missed.
 * Along an axis the ray runs down, the near plane is the box's high one. An empty slot's box
 * lies at +inf and is never entered. */
float4 intersect_boxes(const global BVHNode *n, float3 o, float3 inv_d, float t_max)
{
    float3 c = -o * inv_d, err = fabs(c) * 0x1p-22f;
    float3 c_near = c - err, c_far = c + err;
    float4 x0 = fma(inv_d.x < 0.0f ? n->hi_x : n->lo_x, inv_d.x, c_near.x);
    float4 x1 = fma(inv_d.x < 0.0f ? n->lo_x : n->hi_x, inv_d.x, c_far.x);
    float4 y0 = fma(inv_d.y < 0.0f ? n->hi_y : n->lo_y, inv_d.y, c_near.y);
    float4 y1 = fma(inv_d.y < 0.0f ? n->lo_y : n->hi_y, inv_d.y, c_far.y);
    float4 z0 = fma(inv_d.z < 0.0f ? n->hi_z : n->lo_z, inv_d.z, c_near.z);
    float4 z1 = fma(inv_d.z < 0.0f ? n->lo_z : n->hi_z, inv_d.z, c_far.z);
    float4 t_enter = fmax(fmax(x0, y0), fmax(z0, 0.0f));
    float4 t_exit = fmin(fmin(x1, y1), z1) * BOX_EXIT_SCALE;
    t_exit = fmin(t_exit, t_max);
    return select((float4)(INFINITY), t_enter, t_enter <= t_exit);
}

void intersect_spheres(const SceneData *sc, int first, int count, float3 o, float3 d, int instance, Hit *hit)
{
    COUNT_WORK(sc, PRIMITIVES_TESTED, count);
    for (int i = first; i < first + count; ++i) {
        float t;
#ifdef ALPHA_MASKS
        if (HAS_MASKS(sc)) {
            /* the ray crosses a sphere's surface twice: where the mask cuts the nearer crossing
               out, the farther one may be met */
            float2 crossings = sphere_crossings(sc->spheres[i], o, d);
            t = INFINITY;
            for (int k = 0; k < 2; ++k) {
                float tk = k == 0 ? crossings.x : crossings.y;
                if (tk > 0.0f && tk < hit->t && !masked_out(sc, i, (float2)(0.0f), o + tk * d, d)) {
                    t = tk;
                    break;
                }
            }
        } else
#endif
            t = intersect_range_sphere(sc->spheres[i], o, d, hit->t);
        if (t < hit->t) {
            hit->t = t;
            hit->prim = i;
            SET_INSTANCE(hit, instance);
        }
    }
}

/* A GENERIC program on a GPU tests a leaf's analytic shapes and alpha masks only where the scene
 * has either (intersect_triangles below): skipped by the layout's bits within the loop, their
 * branches still cost every scene registers in its hottest loop (docs/notes/performance-2026-12.md,
 * 2026-12-03, thirtieth session). A scene's own program compiles the loop as it stands, token
 * for token (a wrapper alone once moved ptxas's allocation of one by 4.7 %: 2026-11-30,
 * seventeenth session), and so does a CPU's generic program, which the second loop made slower. */
#if defined(GENERIC) && !defined(CPU_DEVICE)
#define TRIANGLE_TESTS test_triangles
#define SPECIAL_PARAM , int special
#define SPECIAL(test) (special && (test))
#else
#define TRIANGLE_TESTS intersect_triangles
#define SPECIAL_PARAM
#define SPECIAL(test) test
#endif

/* `self`: the primitive the ray leaves (or NO_PRIM), which a plane cannot meet again: skipped.
 * `instance`: the instance drawing them. */
CPU_INLINE void TRIANGLE_TESTS(const SceneData *sc, int first, int count, float3 o, float3 d,
                               PrimId self, int instance, Hit *hit SPECIAL_PARAM)
{
    float3 row_x, row_y, row_z;
    triangle_shear(d, &row_x, &row_y, &row_z);
    COUNT_WORK(sc, PRIMITIVES_TESTED, count);
    for (int i = first; i < first + count; ++i) {
#ifdef SHAPES
        /* an analytic shape: a curved one may be met again by a ray leaving it, so `self` is not
           skipped; the offset origin keeps the ray off the surface it leaves, as a sphere's */
        int kind = SPECIAL(HAS_SHAPES(sc)) ? SHAPE_KIND(&sc->triangles[i]) : 0;
        if (kind) {
            float2 uv;
            float t = intersect_analytic(kind, SHAPE_ROWS(sc, &sc->triangles[i]), o, d, hit->t, &uv);
#ifdef ALPHA_MASKS
            if (t < hit->t && HAS_MASKS(sc) && masked_out(sc, sc->num_spheres + i, uv, o + t * d, d))
                continue;
#endif
            if (t < hit->t) {
                hit->t = t;
                hit->prim = sc->num_spheres + i;
                hit->b1 = uv.x;
                hit->b2 = uv.y;
                SET_INSTANCE(hit, instance);
            }
            continue;
        }
#endif
        if (IS_SELF(self, sc->num_spheres + i, instance))
            continue;
        float b1, b2;
        float t = intersect_triangle(&sc->triangles[i], o, row_x, row_y, row_z, hit->t, &b1, &b2);
#ifdef ALPHA_MASKS
        if (t < hit->t && SPECIAL(HAS_MASKS(sc)) && masked_out(sc, sc->num_spheres + i, (float2)(b1, b2), o + t * d, d))
            continue;
#endif
        if (t < hit->t) {
            hit->t = t;
            hit->prim = sc->num_spheres + i;
            hit->b1 = b1;
            hit->b2 = b2;
            SET_INSTANCE(hit, instance);
        }
    }
}

#if defined(GENERIC) && !defined(CPU_DEVICE)
void intersect_triangles(const SceneData *sc, int first, int count, float3 o, float3 d,
                         PrimId self, int instance, Hit *hit)
{
    if (HAS_SHAPES(sc) || HAS_MASKS(sc))
        test_triangles(sc, first, count, o, d, self, instance, hit, 1);
    else
        test_triangles(sc, first, count, o, d, self, instance, hit, 0);
}
#endif

/* The slots of a node that are leaves the ray enters (leaf: -1 there), as four bits. */
uint leaf_bits(int4 leaf)
{
    return (leaf.x & 1) | (leaf.y & 2) | (leaf.z & 4) | (leaf.w & 8);
}

/* Takes the lowest slot of the bits `leaves`: its leaf's first primitive (or instance) into
 * `first` and its count into `c`. A macro, as the traversal's other steps (ORDER, NEXT_NODE):
 * the variables stay in registers, however the compiler inlines. */
#define NEXT_LEAF(leaves, index, count, first, c) {                                          \
        uint k_ = 31 - clz((leaves) & (0u - (leaves)));                                      \
        (leaves) &= (leaves) - 1;                                                            \
        first = k_ == 0 ? (index).x : k_ == 1 ? (index).y : k_ == 2 ? (index).z : (index).w; \
        c = k_ == 0 ? (count).x : k_ == 1 ? (count).y : k_ == 2 ? (count).z : (count).w;    \
    }

/* Tests the primitives of a node's leaves that the ray enters (t < INFINITY); returns t with the
 * leaves' slots set to INFINITY, leaving the inner children's. NO_TRIANGLES (a build option for
 * scenes of spheres only) leaves the triangle code out, NO_SPHERES (for scenes of triangles
 * only) and LONE_SPHERES (whose tree holds triangles only: trace_ray) the sphere code. Sphere
 * leaves are short, so the four slots are tested unrolled; with triangles, one call of the
 * (inlined) primitive tests in a loop over the leaves' bits keeps the kernel's registers down
 * (docs/notes/performance-2026-11.md, 2026-11-22: a 4-wide BVH). */
CPU_INLINE float4 intersect_leaves(const SceneData *sc, float4 t, int4 count, int4 index, float3 o,
                                   float3 d, PrimId self, int instance, Hit *hit)
{
    int4 leaf = (t < INFINITY) & (count != 0);
#ifdef NO_TRIANGLES
    if (leaf.x) intersect_spheres(sc, index.x, count.x, o, d, instance, hit);
    if (leaf.y) intersect_spheres(sc, index.y, count.y, o, d, instance, hit);
    if (leaf.z) intersect_spheres(sc, index.z, count.z, o, d, instance, hit);
    if (leaf.w) intersect_spheres(sc, index.w, count.w, o, d, instance, hit);
#else
    uint leaves = leaf_bits(leaf);
    while (leaves) {
        int i, c;
        NEXT_LEAF(leaves, index, count, i, c);
#if !defined(NO_SPHERES) && !defined(LONE_SPHERES)
        if (c > 0)
            intersect_spheres(sc, i, c, o, d, instance, hit);
        else
#endif
            intersect_triangles(sc, i, -c, o, d, self, instance, hit);
    }
#endif
    return select(t, (float4)(INFINITY), leaf);
}

/* app/compiler/bvh.py keeps the binary tree at most 30 levels deep, so the 4-wide one at most 15, and
 * traversal pushes at most three nodes per level: 48 entries, for every tree, so that a scene's
 * program can build before its tree does (app/compiler/compiled.py). Sized to each tree (8 to 48
 * entries) it had rendered level on the H100 and on PoCL (docs/notes/performance-2026-11.md,
 * 2026-11-22: the traversal stack sized to the tree). */
#define BVH_STACK_SIZE 48

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


/* Sets `node` to the node to visit next, from a node's children entered at distances t
 * (INFINITY: not entered, or a leaf already tested) with `index` their nodes: the nearest child
 * in front of the nearest hit t_hit, the others in front of it pushed farthest first so that
 * they pop nearest first (a five-comparator network); else the top of the stack, or -1 when it
 * is empty. */
#define NEXT_NODE(t, index, t_hit, stack, top, node) {                   \
        float t0 = (t).x, t1 = (t).y, t2 = (t).z, t3 = (t).w;             \
        int i0 = (index).x, i1 = (index).y, i2 = (index).z, i3 = (index).w; \
        ORDER(t0, i0, t1, i1);                                            \
        ORDER(t2, i2, t3, i3);                                            \
        ORDER(t0, i0, t2, i2);                                            \
        ORDER(t1, i1, t3, i3);                                            \
        ORDER(t1, i1, t2, i2);                                            \
        if (t3 < (t_hit)) stack[top++] = i3;                              \
        if (t2 < (t_hit)) stack[top++] = i2;                              \
        if (t1 < (t_hit)) stack[top++] = i1;                              \
        node = t0 < (t_hit) ? i0 : top == 0 ? -1 : stack[--top];          \
    }

#ifdef FLAT_SPHERES
/* A scene of a few primitives (app/device/features.py: FLAT_MAX) is not traversed: each ray tests them
 * all, FLAT_SPHERES spheres and FLAT_TRIANGLES triangles, constants that let the loops unroll. */
Hit trace_ray(const SceneData *sc, float3 o, float3 d, float t_max, PrimId self, const int any_hit)
{
    Hit hit = {t_max, -1, 0.0f, 0.0f};
    intersect_spheres(sc, 0, FLAT_SPHERES, o, d, 0, &hit);
#ifndef NO_TRIANGLES
    intersect_triangles(sc, 0, FLAT_TRIANGLES, o, d, self, 0, &hit);
#endif
    return hit;
}
#else
/* Walks the tree below node `root` for the ray o + t d, which is in the tree's space (the
 * world's, or instance `instance`'s object's): the nearest hit, or `hit` if none is nearer. */
Hit walk_tree(const SceneData *sc, int root, float3 o, float3 d, PrimId self, int instance,
              const int any_hit, Hit hit)
{
    float3 inv_d = 1.0f / d;
    int stack[BVH_STACK_SIZE];
    int top = 0;
    int node = root;
    do {
        const global BVHNode *n = &sc->nodes[node];
        COUNT_WORK(sc, NODES_VISITED, 1);
        float4 t = intersect_boxes(n, o, inv_d, hit.t);
        int4 index = n->index;
        t = intersect_leaves(sc, t, n->count, index, o, d, self, instance, &hit);
        if (any_hit && hit.prim >= 0)
            return hit;
        NEXT_NODE(t, index, hit.t, stack, top, node);
    } while (node >= 0);
    return hit;
}

#ifdef INSTANCES
/* The tree over the instances, whose leaves' instances the ray enters in their objects' space
 * (d is not normalised there, so that t stays the world's). Objects hold no instances, so the
 * two walks have stacks of their own. */
Hit walk_instances(const SceneData *sc, float3 o, float3 d, float t_max, PrimId self, const int any_hit)
{
    Hit hit = {t_max, -1, 0.0f, 0.0f, -1};
    float3 inv_d = 1.0f / d;
    int stack[BVH_STACK_SIZE];
    int top = 0;
    int node = 0;
    do {
        const global BVHNode *n = &sc->nodes[node];
        COUNT_WORK(sc, NODES_VISITED, 1);
        float4 t = intersect_boxes(n, o, inv_d, hit.t);
        int4 index = n->index, count = n->count;
        int4 leaf = (t < INFINITY) & (count != 0);
        uint leaves = leaf_bits(leaf);
        while (leaves) {
            int first, c;
            NEXT_LEAF(leaves, index, count, first, c);
            for (int i = first; i < first + c; ++i) {
                const global Instance *inst = &sc->instances[i];
                hit = walk_tree(sc, inst->root, transform_point(inst->to_object, o),
                                transform_vector(inst->to_object, d), self, i, any_hit, hit);
                if (any_hit && hit.prim >= 0)
                    return hit;
            }
        }
        t = select(t, (float4)(INFINITY), leaf);
        NEXT_NODE(t, index, hit.t, stack, top, node);
    } while (node >= 0);
    return hit;
}
#endif

/* A one-level tree over the world's primitives. With LONE_SPHERES, a scene's few spheres
 * (app/device/features.py: LONE_MAX) are not in the tree, which holds its triangles alone: every ray
 * tests them first, and their nearest hit bounds the walk. Its hits are drawn by no instance
 * (-1), which a GENERIC program, built with INSTANCES, tells apart (surface_at). */
Hit walk_world(const SceneData *sc, float3 o, float3 d, float t_max, PrimId self, const int any_hit)
{
    Hit hit = {t_max, -1, 0.0f, 0.0f};
    SET_INSTANCE(&hit, -1);
#ifdef GENERIC
    if (sc->layout & LAYOUT_FLAT) {    /* as a FLAT_SPHERES program tests them, but in loops */
        intersect_spheres(sc, 0, sc->num_spheres, o, d, -1, &hit);
        intersect_triangles(sc, 0, sc->layout >> LAYOUT_FLAT_TRIANGLES, o, d, self, -1, &hit);
        return hit;
    }
    int lone = sc->layout & LAYOUT_LONE_SPHERES ? sc->num_spheres : 0;
#elif defined(LONE_SPHERES)
    const int lone = LONE_SPHERES;
#else
    const int lone = 0;
#endif
    if (lone) {
        intersect_spheres(sc, 0, lone, o, d, -1, &hit);
        if (any_hit && hit.prim >= 0)
            return hit;
    }
    return walk_tree(sc, 0, o, d, self, -1, any_hit, hit);
}

Hit trace_ray(const SceneData *sc, float3 o, float3 d, float t_max, PrimId self, const int any_hit)
{
#ifdef GENERIC
    if (sc->layout & LAYOUT_INSTANCES)
        return walk_instances(sc, o, d, t_max, self, any_hit);
    return walk_world(sc, o, d, t_max, self, any_hit);
#elif defined(INSTANCES)
    return walk_instances(sc, o, d, t_max, self, any_hit);
#else
    return walk_world(sc, o, d, t_max, self, any_hit);
#endif
}
#endif

/* The nearest hit along o + t d, t in (0, t_max), skipping the surface `self` (the one the ray
 * leaves, or NO_PRIM). */
Hit intersect_scene(const SceneData *sc, float3 o, float3 d, float t_max, PrimId self)
{
    return trace_ray(sc, o, d, t_max, self, 0);
}

/* Whether anything but `self` lies on o + t d for t in (0, t_max). */
int occluded(const SceneData *sc, float3 o, float3 d, float t_max, PrimId self)
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
#ifdef INSTANCES
    int instance;    /* the instance that draws it */
#endif
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


/* The surface at hit, found along o + t d, in world space. */
Surface surface_at(const SceneData *sc, const Hit *hit, float3 o, float3 d)
{
    Surface s;
    float3 error;
    s.prim = hit->prim;
#ifdef TEXTURES
    s.b = (float2)(hit->b1, hit->b2);
#endif
#if defined(NORMAL_MAPS) || defined(MEDIA)
    s.side = 1.0f;
#endif
#ifdef INSTANCES
    s.instance = hit->instance;
    const global Instance *inst = &sc->instances[max(hit->instance, 0)];
    if (INSTANCED(hit->instance)) {
        o = transform_point(inst->to_object, o);
        d = transform_vector(inst->to_object, d);
    }
#endif
#ifndef NO_TRIANGLES
    if (hit->prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[hit->prim - sc->num_spheres];
#ifdef SHAPES
        if (SHAPE_KIND(tri)) {
            analytic_surface(SHAPE_KIND(tri), SHAPE_ROWS(sc, tri), (float2)(hit->b1, hit->b2), &s.p, &error, &s.ng);
            s.ns = s.ng;
        } else
#endif
        triangle_surface(tri, sc->normals, hit->b1, hit->b2, &s.p, &error, &s.ng, &s.ns);
    } else
#endif
    {
        sphere_surface(sc->spheres[hit->prim], o, d, hit->t, &s.p, &error, &s.ng);
        s.ns = s.ng;
#ifdef TEXTURES
        s.b = (float2)(0.0f);
#endif
    }
#ifdef INSTANCES
    if (INSTANCED(hit->instance)) {
        error = transform_error(inst->to_world, s.p, error);
        s.p = transform_point(inst->to_world, s.p);
        s.ng = transform_normal(inst->to_object, s.ng);
        s.ns = transform_normal(inst->to_object, s.ns);
    }
#endif
    s.offset = error_offset(s.ng, error);
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

/* The texture coordinates of point p on primitive prim, a triangle's barycentric weights b or
 * an analytic shape's parameters (a program for a scene with textures has them). */
float2 surface_uv(const SceneData *sc, int prim, float2 b, float3 p)
{
#ifndef NO_TRIANGLES
    if (prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[prim - sc->num_spheres];
#ifdef SHAPES
        if (SHAPE_KIND(tri))
            return analytic_texture_uv(SHAPE_ROWS(sc, tri), b);
#endif
        return triangle_uv(tri, sc->uvs, b.x, b.y);
    }
#endif
    return range_sphere_uv(sc->spheres[prim], p);
}
