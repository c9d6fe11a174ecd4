/* Ray queries against the whole scene: the nearest hit through the BVH, over spheres and
 * triangles together. */

typedef struct {
    float t;
    int prim;     /* primitive index (types.h); -1: no hit */
    float b1;     /* a triangle hit's barycentric weights of v1 and v2 */
    float b2;
} Hit;

/* Entry distance of the ray into a child's box, or INFINITY if it misses or enters past t_max.
 * The exit distance is scaled up by 1 + 2 gamma(3), the rounding of its computation (pbrt-v4
 * section 6.8.2), so that a ray grazing a thin box (a sliver triangle's) is never missed. */
#define BOX_EXIT_SCALE 1.0000003576f
float intersect_box(const global BVHChild *c, float3 o, float3 inv_d, float t_max)
{
    float3 lo = ((float3)(c->lo[0], c->lo[1], c->lo[2]) - o) * inv_d;
    float3 hi = ((float3)(c->hi[0], c->hi[1], c->hi[2]) - o) * inv_d;
    float3 t_lo = fmin(lo, hi), t_hi = fmax(lo, hi);
    float t_enter = fmax(fmax(t_lo.x, t_lo.y), fmax(t_lo.z, 0.0f));
    float t_exit = fmin(fmin(t_hi.x, t_hi.y), t_hi.z) * BOX_EXIT_SCALE;
    t_exit = fmin(t_exit, t_max);
    return t_enter <= t_exit ? t_enter : INFINITY;
}

void intersect_spheres(const SceneData *sc, int first, int count, float3 o, float3 d, Hit *hit)
{
    for (int i = first; i < first + count; ++i) {
        float t = intersect_sphere(sc->spheres[i], o, d, hit->t);
        if (t < hit->t) {
            hit->t = t;
            hit->prim = i;
        }
    }
}

void intersect_triangles(const SceneData *sc, int first, int count, float3 o, float3 d, Hit *hit)
{
    float3 row_x, row_y, row_z;
    triangle_shear(d, &row_x, &row_y, &row_z);
    for (int i = first; i < first + count; ++i) {
        float b1, b2;
        float t = intersect_triangle(&sc->triangles[i], o, row_x, row_y, row_z, hit->t, &b1, &b2);
        if (t < hit->t) {
            hit->t = t;
            hit->prim = sc->num_spheres + i;
            hit->b1 = b1;
            hit->b2 = b2;
        }
    }
}

/* NO_TRIANGLES (a build option for scenes of spheres only) leaves the triangle code out. */
void intersect_leaf(const SceneData *sc, const global BVHChild *c, float3 o, float3 d, Hit *hit)
{
#ifdef NO_TRIANGLES
    intersect_spheres(sc, c->index, c->count, o, d, hit);
#else
    if (c->count > 0)
        intersect_spheres(sc, c->index, c->count, o, d, hit);
    else
        intersect_triangles(sc, c->index, -c->count, o, d, hit);
#endif
}

/* app/bvh.py keeps the tree at most 30 levels deep, and traversal pushes one node per level. */
#define BVH_STACK_SIZE 32

/* The hit along o + t d, t in (0, t_max): the nearest one, or with any_hit (a constant at each
 * call, so the compiler builds two traversals) the first one found, which is all a shadow ray
 * needs to know. Children are visited nearer-first. The stack holds node indices only (small
 * private memory keeps GPU occupancy up); a popped node's children are tested against the
 * nearest hit found meanwhile. Rays leaving a surface start at an offset origin
 * (kernels/spawn.cl), so no primitive needs to be skipped. */
Hit trace_ray(const SceneData *sc, float3 o, float3 d, float t_max, const int any_hit)
{
    Hit hit = {t_max, -1, 0.0f, 0.0f};
    float3 inv_d = 1.0f / d;
    int stack[BVH_STACK_SIZE];
    int top = 0;
    int node = 0;
    for (;;) {
        const global BVHChild *c0 = &sc->nodes[node].child[0];
        const global BVHChild *c1 = &sc->nodes[node].child[1];
        float t0 = intersect_box(c0, o, inv_d, hit.t);
        float t1 = intersect_box(c1, o, inv_d, hit.t);
        if (t0 < INFINITY && c0->count != 0) {
            intersect_leaf(sc, c0, o, d, &hit);
            t0 = INFINITY;
        }
        if (t1 < INFINITY && c1->count != 0) {
            intersect_leaf(sc, c1, o, d, &hit);
            t1 = INFINITY;
        }
        if (any_hit && hit.prim >= 0)
            return hit;
        /* a leaf hit may have moved the nearest hit in front of the other child */
        t0 = t0 < hit.t ? t0 : INFINITY;
        t1 = t1 < hit.t ? t1 : INFINITY;
        if (t0 < INFINITY && t1 < INFINITY) {
            int near = t0 <= t1 ? c0->index : c1->index;
            stack[top++] = t0 <= t1 ? c1->index : c0->index;
            node = near;
            continue;
        }
        if (t0 < INFINITY) { node = c0->index; continue; }
        if (t1 < INFINITY) { node = c1->index; continue; }
        if (top == 0)
            return hit;
        node = stack[--top];
    }
}

Hit intersect_scene(const SceneData *sc, float3 o, float3 d, float t_max)
{
    return trace_ray(sc, o, d, t_max, 0);
}

/* Whether anything lies on o + t d for t in (0, t_max). */
int occluded(const SceneData *sc, float3 o, float3 d, float t_max)
{
    return trace_ray(sc, o, d, t_max, 1).prim >= 0;
}

/* What a path needs of the surface it hit. */
typedef struct {
    float3 p;        /* the point */
    float3 ng;       /* unit geometric normal, on the front side */
    float3 ns;       /* unit shading normal, in ng's hemisphere */
    float offset;    /* how far rays leaving p start from it along ng (kernels/spawn.cl) */
} Surface;

Surface surface_at(const SceneData *sc, const Hit *hit, float3 o, float3 d)
{
    Surface s;
    float3 error;
#ifndef NO_TRIANGLES
    if (hit->prim >= sc->num_spheres) {
        triangle_surface(&sc->triangles[hit->prim - sc->num_spheres], sc->normals, hit->b1,
                         hit->b2, &s.p, &error, &s.ng, &s.ns);
        s.offset = error_offset(s.ng, error);
        return s;
    }
#endif
    sphere_surface(sc->spheres[hit->prim], o, d, hit->t, &s.p, &error, &s.ng);
    s.ns = s.ng;
    s.offset = error_offset(s.ng, error);
    return s;
}
