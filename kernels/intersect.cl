/* Ray queries: one sphere, one box, and the nearest hit through the BVH. */

typedef struct {
    float t;
    int sphere;   /* index into the BVH-ordered sphere array; -1: no hit */
} Hit;

/* Nearest t in (0, t_max) where o + t d meets the sphere, or INFINITY; d must be unit length.
 * The discriminant is computed as r^2 - |f - (f.d) d|^2 rather than b^2 - c, and the two roots
 * as c / q and q, following Haines et al., "Precision Improvements for Ray/Sphere Intersection",
 * Ray Tracing Gems, ch. 7 (2019): both stay accurate for the r = 1000 ground seen from afar. */
float intersect_sphere(Sphere s, float3 o, float3 d, float t_max)
{
    float3 f = o - s.xyz;
    float b = dot(f, d);
    float3 l = f - b * d;
    float disc = s.w * s.w - dot(l, l);
    if (disc < 0.0f)
        return INFINITY;
    float c = dot(f, f) - s.w * s.w;
    float q = -(b + copysign(sqrt(disc), b));
    float t0 = c / q, t1 = q;
    float t_near = fmin(t0, t1), t_far = fmax(t0, t1);
    /* A ray starting inside the sphere (c < 0) meets it only on the way out. */
    float t = t_near > 0.0f ? t_near : t_far;
    return (t > 0.0f && t < t_max) ? t : INFINITY;
}

/* Entry distance of the ray into a child's box, or INFINITY if it misses or enters past t_max. */
float intersect_box(const global BVHChild *c, float3 o, float3 inv_d, float t_max)
{
    float3 lo = ((float3)(c->lo[0], c->lo[1], c->lo[2]) - o) * inv_d;
    float3 hi = ((float3)(c->hi[0], c->hi[1], c->hi[2]) - o) * inv_d;
    float3 t_lo = fmin(lo, hi), t_hi = fmax(lo, hi);
    float t_enter = fmax(fmax(t_lo.x, t_lo.y), fmax(t_lo.z, 0.0f));
    float t_exit = fmin(fmin(t_hi.x, t_hi.y), fmin(t_hi.z, t_max));
    return t_enter <= t_exit ? t_enter : INFINITY;
}

void intersect_leaf(const global Sphere *spheres, int first, int count, float3 o, float3 d,
                    int skip, Hit *hit)
{
    for (int i = first; i < first + count; ++i) {
        if (i == skip)
            continue;
        float t = intersect_sphere(spheres[i], o, d, hit->t);
        if (t < hit->t) {
            hit->t = t;
            hit->sphere = i;
        }
    }
}

/* app/bvh.py keeps the tree at most 30 levels deep, and traversal pushes one node per level. */
#define BVH_STACK_SIZE 32

/* Nearest hit along o + t d, t in (0, t_max), ignoring sphere `skip` (the one the ray leaves:
 * a ray leaving a convex surface into its outer hemisphere cannot meet it again, which removes
 * self-intersection without any epsilon). Children are visited nearer-first. The stack holds
 * node indices only (small private memory keeps GPU occupancy up); a popped node's children
 * are tested against the nearest hit found meanwhile. */
Hit intersect_scene(const global BVHNode *nodes, const global Sphere *spheres, float3 o, float3 d,
                    float t_max, int skip)
{
    Hit hit = {t_max, -1};
    float3 inv_d = 1.0f / d;
    int stack[BVH_STACK_SIZE];
    int top = 0;
    int node = 0;
    for (;;) {
        const global BVHChild *c0 = &nodes[node].child[0];
        const global BVHChild *c1 = &nodes[node].child[1];
        float t0 = intersect_box(c0, o, inv_d, hit.t);
        float t1 = intersect_box(c1, o, inv_d, hit.t);
        if (t0 < INFINITY && c0->count > 0) {
            intersect_leaf(spheres, c0->index, c0->count, o, d, skip, &hit);
            t0 = INFINITY;
        }
        if (t1 < INFINITY && c1->count > 0) {
            intersect_leaf(spheres, c1->index, c1->count, o, d, skip, &hit);
            t1 = INFINITY;
        }
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
