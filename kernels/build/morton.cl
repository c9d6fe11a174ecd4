/* Morton codes of primitives' centroids (Morton 1966; Lauterbach et al., "Fast BVH Construction
 * on GPUs", 2009): 21 bits per axis of the centroid's place in the centroids' bounds, interleaved
 * into 63 bits, so that sorting by code lays the primitives along a Z-order curve. app/compiler/bvh.py
 * sorts them; PLOC's clusters then look for neighbours along that order.
 *
 * box: per node two float4, lo then hi; primitives first..first+count-1 are coded.
 * c_lo, scale: the bounds of (lo + hi) (twice the centroids) and (2^21 - 1) / their extent. */

ulong spread_bits(uint v)
{
    ulong x = v & 0x1FFFFF;
    x = (x | x << 32) & 0x1F00000000FFFFUL;
    x = (x | x << 16) & 0x1F0000FF0000FFUL;
    x = (x | x << 8) & 0x100F00F00F00F00FUL;
    x = (x | x << 4) & 0x10C30C30C30C30C3UL;
    x = (x | x << 2) & 0x1249249249249249UL;
    return x;
}

kernel void morton_codes(global const float4 *box, int first, int count, float4 c_lo, float4 scale,
                         global ulong *code)
{
    int i = get_global_id(0);
    if (i >= count)
        return;
    float4 q = (box[2 * (first + i)] + box[2 * (first + i) + 1] - c_lo) * scale;
    q = clamp(q, 0.0f, 2097151.0f);
    code[i] = spread_bits((uint)q.x) << 2 | spread_bits((uint)q.y) << 1 | spread_bits((uint)q.z);
}

/* The clusters PLOC starts from: the primitives in code order (order: from the host's sort). */
kernel void first_clusters(global const float4 *box, global const int *order, int first, int count,
                           global int *cluster, global float4 *cluster_box)
{
    int i = get_global_id(0);
    if (i >= count)
        return;
    int p = first + order[i];
    cluster[i] = p;
    cluster_box[2 * i] = box[2 * p];
    cluster_box[2 * i + 1] = box[2 * p + 1];
}
