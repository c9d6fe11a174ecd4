/* The clustered binary tree made into the 4-wide BVHNode array that kernels/bvh.cl walks, in sweeps
 * over the batches of app/compiler/bvh.py's build (a batch's nodes depend only on earlier batches below
 * them, so one launch per batch and sweep, bottom-up or top-down):
 *
 * 1. collapse_up: primitives under each node and its SAH cost relative to its own area; a
 *    subtree of at most MAX_LEAF_SIZE primitives becomes one leaf where that is cheaper than its
 *    split (the surface area heuristic, MacDonald and Booth 1990, as pbrt-v4's builder decides).
 * 2. mark_inner_down: depth, and whether a node is an inner BVH node: not a primitive, not a leaf
 *    by the SAH, not inside a leaf, not at MAX_DEPTH (kernels/bvh.cl's stack is sized for it; a
 *    leaf there keeps all its primitives).
 * 3. count_inner_up: the 4-wide nodes in each subtree. Inner nodes at even depths become 4-wide
 *    nodes; those at odd depths give their children to their parent's (so the 4-wide tree is
 *    half as deep, and a node holds 2 to 4 children).
 * 4. number_down: each 4-wide node's place in depth-first order, each node's first primitive.
 * 5. write_nodes: the BVHNodes and the primitives' order.
 *
 * child: per node (left, right), primitives (-1, -1); box: per node two float4, lo then hi.
 * Nodes `first`..`first + count - 1` are one batch. */

#pragma OPENCL FP_CONTRACT OFF

/* MAX_LEAF_SIZE, MAX_DEPTH and TRAVERSAL_COST come as build options from app/compiler/bvh.py. */

/* Half the surface area; extents clamped to FLT_MAX so that a huge flat box gives inf, never NaN. */
float half_area(global const float4 *box, int k)
{
    float4 e = fmin(fmax(box[2 * k + 1] - box[2 * k], 0.0f), FLT_MAX);
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

kernel void collapse_up(global const int2 *child, global const float4 *box, int first, int count,
                        global int *prims, global float *cost, global uchar *sah_leaf)
{
    int k = first + get_global_id(0);
    if (k >= first + count)
        return;
    int2 c = child[k];
    int n = prims[c.x] + prims[c.y];
    float area = half_area(box, k);
    float below = half_area(box, c.x) * cost[c.x] + half_area(box, c.y) * cost[c.y];
    float split = TRAVERSAL_COST + (area > 0.0f ? below / area : cost[c.x] + cost[c.y]);
    int leaf = n <= MAX_LEAF_SIZE && n <= split;   /* false for a NaN split */
    prims[k] = n;
    cost[k] = leaf ? n : split;
    sah_leaf[k] = leaf;
}

kernel void mark_inner_down(global const int2 *child, int first, int count, int num_primitives,
                            global const uchar *sah_leaf, global uchar *inner, global int *depth)
{
    int k = first + get_global_id(0);
    if (k >= first + count || !inner[k])
        return;
    int2 c = child[k];
    int d = depth[k] + 1;
    depth[c.x] = depth[c.y] = d;
    inner[c.x] = c.x >= num_primitives && !sah_leaf[c.x] && d < MAX_DEPTH;
    inner[c.y] = c.y >= num_primitives && !sah_leaf[c.y] && d < MAX_DEPTH;
}

/* Whether inner node k becomes a 4-wide node. */
int is_wide(global const uchar *inner, global const int *depth, int k)
{
    return inner[k] && (depth[k] & 1) == 0;
}

kernel void count_inner_up(global const int2 *child, int first, int count,
                           global const uchar *inner, global const int *depth, global int *below)
{
    int k = first + get_global_id(0);
    if (k >= first + count)
        return;
    int2 c = child[k];
    below[k] = inner[k] ? is_wide(inner, depth, k) + below[c.x] + below[c.y] : 0;
}

kernel void number_down(global const int2 *child, int first, int count, global const int *prims,
                        global const uchar *inner, global const int *depth,
                        global const int *below, global int *number, global int *first_prim)
{
    int k = first + get_global_id(0);
    if (k >= first + count)
        return;
    int2 c = child[k];
    int wide = is_wide(inner, depth, k);
    first_prim[c.x] = first_prim[k];
    first_prim[c.y] = first_prim[k] + prims[c.x];
    number[c.x] = number[k] + wide;
    number[c.y] = number[k] + wide + below[c.x];
}

/* One child slot of a 4-wide node. */
typedef struct {
    float3 lo, hi;
    int index, count;
} Slot;

/* Node c as a slot: its box widened by one float step (covering the rounding of centre -/+ radius
 * and of the corners' float32 values) and what it holds. A leaf indexes its kind's own array
 * (kernels/types.h), a triangle leaf's count being negative: the spheres' tree comes first in
 * depth-first order, so triangles' numbers are shifted by num_spheres. */
Slot slot_of(global const float4 *box, int c, global const uchar *inner, global const int *number,
             global const int *first_prim, global const int *prims, int num_spheres)
{
    Slot s;
    s.lo = nextafter(box[2 * c].xyz, (float3)(-INFINITY));
    s.hi = nextafter(box[2 * c + 1].xyz, (float3)(INFINITY));
    if (inner[c]) {
        s.index = number[c];
        s.count = 0;
    } else if (first_prim[c] < num_spheres) {
        s.index = first_prim[c];
        s.count = prims[c];
    } else {
        s.index = first_prim[c] - num_spheres;
        s.count = -prims[c];
    }
    return s;
}

Slot empty_slot(void)
{
    Slot s = {(float3)(INFINITY), (float3)(INFINITY), -1, 0};
    return s;
}

/* Over every node: a primitive writes its place in the order; an inner node at an even depth
 * writes its 4-wide node, whose slots are its children, an inner child's two children in its
 * stead; an inner node with a leaf child writes that leaf's depth into max_depth. */
kernel void write_nodes(global const int2 *child, global const float4 *box, int num_nodes,
                        int num_primitives, int num_spheres, global const uchar *inner,
                        global const int *number, global const int *first_prim,
                        global const int *prims, global const int *depth,
                        global BVHNode *nodes, global int *order, global int *max_depth)
{
    int k = get_global_id(0);
    if (k >= num_nodes)
        return;
    if (k < num_primitives)
        order[first_prim[k]] = k;
    if (!inner[k])
        return;
    int2 c = child[k];
    if (!inner[c.x] || !inner[c.y])
        atomic_max(max_depth, depth[k] + 1);
    if (depth[k] & 1)
        return;
    Slot s[4];
    for (int side = 0; side < 2; ++side) {
        int h = side ? c.y : c.x;
        if (inner[h]) {
            s[2 * side] = slot_of(box, child[h].x, inner, number, first_prim, prims, num_spheres);
            s[2 * side + 1] = slot_of(box, child[h].y, inner, number, first_prim, prims, num_spheres);
        } else {
            s[2 * side] = slot_of(box, h, inner, number, first_prim, prims, num_spheres);
            s[2 * side + 1] = empty_slot();
        }
    }
    global BVHNode *n = &nodes[number[k]];
    n->lo_x = (float4)(s[0].lo.x, s[1].lo.x, s[2].lo.x, s[3].lo.x);
    n->lo_y = (float4)(s[0].lo.y, s[1].lo.y, s[2].lo.y, s[3].lo.y);
    n->lo_z = (float4)(s[0].lo.z, s[1].lo.z, s[2].lo.z, s[3].lo.z);
    n->hi_x = (float4)(s[0].hi.x, s[1].hi.x, s[2].hi.x, s[3].hi.x);
    n->hi_y = (float4)(s[0].hi.y, s[1].hi.y, s[2].hi.y, s[3].hi.y);
    n->hi_z = (float4)(s[0].hi.z, s[1].hi.z, s[2].hi.z, s[3].hi.z);
    n->index = (int4)(s[0].index, s[1].index, s[2].index, s[3].index);
    n->count = (int4)(s[0].count, s[1].count, s[2].count, s[3].count);
}
