/* The clustered binary tree made into the BVH_NODE array that kernels/bvh.cl walks, in sweeps
 * over the batches of app/bvh.py's build (a batch's nodes depend only on earlier batches below
 * them, so one launch per batch and sweep, bottom-up or top-down):
 *
 * 1. collapse_up: primitives under each node and its SAH cost relative to its own area; a
 *    subtree of at most MAX_LEAF_SIZE primitives becomes one leaf where that is cheaper than its
 *    split (the surface area heuristic, MacDonald and Booth 1990, as pbrt-v4's builder decides).
 * 2. mark_inner_down: depth, and whether a node is an inner BVH node: not a primitive, not a leaf
 *    by the SAH, not inside a leaf, not at MAX_DEPTH (kernels/bvh.cl keeps a 32-entry stack; a
 *    leaf there keeps all its primitives).
 * 3. count_inner_up: inner nodes in each subtree.
 * 4. number_down: each inner node's place in depth-first order, each node's first primitive.
 * 5. write_nodes: the BVH_NODEs and the primitives' order.
 *
 * child: per node (left, right), primitives (-1, -1); box: per node two float4, lo then hi.
 * Nodes `first`..`first + count - 1` are one batch. */

#pragma OPENCL FP_CONTRACT OFF

#define MAX_LEAF_SIZE 4
#define MAX_DEPTH 30
#define TRAVERSAL_COST 0.5f

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

kernel void count_inner_up(global const int2 *child, int first, int count,
                           global const uchar *inner, global int *below)
{
    int k = first + get_global_id(0);
    if (k >= first + count)
        return;
    int2 c = child[k];
    below[k] = inner[k] ? 1 + below[c.x] + below[c.y] : 0;
}

kernel void number_down(global const int2 *child, int first, int count, global const int *prims,
                        global const int *below, global int *number, global int *first_prim)
{
    int k = first + get_global_id(0);
    if (k >= first + count)
        return;
    int2 c = child[k];
    first_prim[c.x] = first_prim[k];
    first_prim[c.y] = first_prim[k] + prims[c.x];
    number[c.x] = number[k] + 1;
    number[c.y] = number[k] + 1 + below[c.x];
}

/* A child slot: its box widened by one float step (covering the rounding of centre -/+ radius and
 * of the corners' float32 values) and what it holds. A leaf indexes its kind's own array
 * (kernels/types.h), a triangle leaf's count being negative: the spheres' tree comes first in
 * depth-first order, so triangles' numbers are shifted by num_spheres. */
BVHChild child_slot(global const float4 *box, int c, global const uchar *inner,
                    global const int *number, global const int *first_prim,
                    global const int *prims, int num_spheres)
{
    BVHChild s;
    float4 lo = nextafter(box[2 * c], (float4)(-INFINITY));
    float4 hi = nextafter(box[2 * c + 1], (float4)(INFINITY));
    s.lo[0] = lo.x; s.lo[1] = lo.y; s.lo[2] = lo.z;
    s.hi[0] = hi.x; s.hi[1] = hi.y; s.hi[2] = hi.z;
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

/* Over every node: an inner node writes its BVH_NODE, a primitive its place in the order, a leaf
 * its depth into max_depth. */
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
    nodes[number[k]].child[0] = child_slot(box, c.x, inner, number, first_prim, prims, num_spheres);
    nodes[number[k]].child[1] = child_slot(box, c.y, inner, number, first_prim, prims, num_spheres);
    if (!inner[c.x] || !inner[c.y])
        atomic_max(max_depth, depth[k] + 1);
}
