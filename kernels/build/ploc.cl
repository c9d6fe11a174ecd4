/* A pass of PLOC, parallel locally-ordered clustering (Meister and Bittner, "Parallel
 * Locally-Ordered Clustering for Bounding Volume Hierarchy Construction", IEEE TVCG 2018).
 *
 * Clusters lie in Morton order. Each cluster looks at the `radius` clusters on either side and
 * picks the one whose union with it has the smallest surface area (the distance of the paper's
 * section 3, find_nearest). Mutual nearest neighbours merge into a new node in the place of the
 * first (merge_clusters); where the new nodes and the surviving clusters go is an exclusive
 * prefix sum of two flags, per work-group here (mark_merges) and over the groups on the host.
 *
 * Ties are broken by a total order on pairs, the same seen from both ends: (area, index
 * distance k, whether (lower index / k) is odd, lower index). So the pair smallest in that order
 * is always mutual and every pass merges at least one pair, and identical boxes pair up as
 * (0,1), (2,3), ... instead of all choosing cluster 0. The area is computed from the union's
 * corners, which fmin/fmax give bit for bit the same from either end; extents are clamped to
 * FLT_MAX so that a huge flat box has area inf, never NaN (inf * 0).
 *
 * Without contraction into fused multiply-adds every operation here is correctly rounded, so every
 * device finds the same neighbours and builds the same tree.
 *
 * box: per cluster two float4, lo then hi (w unused); nearest: out, per cluster.
 */
#pragma OPENCL FP_CONTRACT OFF

float union_area(float3 lo, float3 hi, global const float4 *box, int j)
{
    float3 e = fmin(fmax(hi, box[2 * j + 1].xyz) - fmin(lo, box[2 * j].xyz), FLT_MAX);
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

kernel void find_nearest(global const float4 *box, int count, int radius, global int *nearest)
{
    int i = get_global_id(0);
    if (i >= count)
        return;
    float3 lo = box[2 * i].xyz, hi = box[2 * i + 1].xyz;
    float best = INFINITY;
    int best_j = -1;
    /* k ascending, and at each k the right one first: only a tie of the two sides at one k
     * needs the pair order's third key (and its division) */
    for (int k = 1; k <= radius; ++k) {
        if (i + k < count) {
            float a = union_area(lo, hi, box, i + k);
            if (a < best || best_j < 0) {
                best = a;
                best_j = i + k;
            }
        }
        if (i - k >= 0) {
            float a = union_area(lo, hi, box, i - k);
            if (a < best || best_j < 0 || (a == best && best_j == i + k && ((i / k) & 1))) {
                best = a;
                best_j = i - k;
            }
        }
    }
    nearest[i] = best_j;
}

#define SCAN_GROUP 256

/* Per cluster two flags, (merges: it starts a new node, survives: it stays a cluster), and their
 * exclusive prefix sums within the work-group (a Hillis-Steele scan in local memory); each
 * group's totals go to group_sum. */
kernel void mark_merges(global const int *nearest, int count, global int2 *prefix,
                        global int2 *group_sum)
{
    local int2 scan[SCAN_GROUP];
    int i = get_global_id(0), l = get_local_id(0);
    int2 flags = (int2)(0, 0);
    if (i < count) {
        int j = nearest[i];
        int mutual = nearest[j] == i;
        flags = (int2)(mutual && i < j, !(mutual && i > j));
    }
    scan[l] = flags;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int offset = 1; offset < SCAN_GROUP; offset <<= 1) {
        int2 add = l >= offset ? scan[l - offset] : (int2)(0, 0);
        barrier(CLK_LOCAL_MEM_FENCE);
        scan[l] += add;
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    if (i < count)
        prefix[i] = scan[l] - flags;
    if (l == SCAN_GROUP - 1)
        group_sum[get_group_id(0)] = scan[l];
}

/* The new nodes, numbered from `made` (children and boxes into the tree), and the surviving
 * clusters compacted into cluster_out / box_out. group_start: the groups' exclusive prefix sums. */
kernel void merge_clusters(global const int *nearest, int count, global const int2 *prefix,
                           global const int2 *group_start, int made,
                           global const int *cluster, global const float4 *cluster_box,
                           global int *cluster_out, global float4 *box_out,
                           global int2 *child, global float4 *box)
{
    int i = get_global_id(0);
    if (i >= count)
        return;
    int j = nearest[i];
    int mutual = nearest[j] == i;
    if (mutual && i > j)
        return;
    int2 at = prefix[i] + group_start[get_group_id(0)];
    float4 lo = cluster_box[2 * i], hi = cluster_box[2 * i + 1];
    int node = cluster[i];
    if (mutual) {
        lo = fmin(lo, cluster_box[2 * j]);
        hi = fmax(hi, cluster_box[2 * j + 1]);
        node = made + at.x;
        child[node] = (int2)(cluster[i], cluster[j]);
        box[2 * node] = lo;
        box[2 * node + 1] = hi;
    }
    cluster_out[at.y] = node;
    box_out[2 * at.y] = lo;
    box_out[2 * at.y + 1] = hi;
}
