/* The nearest-neighbour search of PLOC, parallel locally-ordered clustering (Meister and Bittner,
 * "Parallel Locally-Ordered Clustering for Bounding Volume Hierarchy Construction", IEEE TVCG
 * 2018): the step of app/bvh.py's builder that costs the most and parallelises perfectly.
 *
 * Clusters lie in Morton order. Each cluster looks at the `radius` clusters on either side and
 * picks the one whose union with it has the smallest surface area (the distance of the paper's
 * section 3). Mutual nearest neighbours are merged on the host.
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
