/* Choosing a light from the light tree (app/lights/tree.py), in proportion to each node's
 * importance at the shading point: pbrt-v4's BVHLightSampler (section 12.6.3), after Conty
 * Estevez and Kulla, "Importance Sampling of Many Lights with Adaptive Tree Splitting" (2018).
 * Compiled in (LIGHT_TREE) only for scenes of many lights: a table entry of type LIGHT_TREE_ROOT
 * stands for all the lights that have a place (area lights, points and spots), whose entries
 * follow the alias table's, each knowing its leaf (`alias`), each leaf its entry.
 *
 * At every node the two children are weighed by their importance and one is taken with 32
 * random bits against a threshold t: the first child's probability is exactly t / 2^32, which
 * the density divides by, and which a path that hits a light recomputes on the way up from the
 * light's leaf (tree_pick_probability) to weigh the hit by MIS. */

#define LIGHT_TREE_DEPTH 64     /* deeper than app/lights/tree.py builds */

/* cos(max(0, a - b)) and sin(max(0, a - b)) from the angles' sines and cosines. */
float cos_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b)
{
    return cos_a > cos_b ? 1.0f : cos_a * cos_b + sin_a * sin_b;
}

float sin_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b)
{
    return cos_a > cos_b ? 0.0f : sin_a * cos_b - cos_a * sin_b;
}

/* A node's estimate of what its lights give point x of normal n (0: no normal): their power
 * over the squared distance to its box's centre, times the cosine of the smallest angle
 * between the direction to x and any light's emission, and of the smallest angle of incidence
 * at x, each widened by the cone of directions the box subtends from x (pbrt-v4's
 * LightBounds::Importance). 0 where no light of the node can reach x. */
float node_importance(const global LightNode *node, float3 x, float3 n)
{
    float power = node->lo.w;
    if (!(power > 0.0f))
        return 0.0f;
    float3 lo = node->lo.xyz, hi = node->hi.xyz;
    float3 v = x - 0.5f * (lo + hi);
    float dist2 = dot(v, v);
    float radius2 = 0.25f * dot(hi - lo, hi - lo);
    /* the directions from x that reach the box's bounding sphere: all of them from inside */
    float cos_b = dist2 < radius2 ? -1.0f : sqrt(fmax(0.0f, 1.0f - radius2 / dist2));
    float sin_b = sqrt(fmax(0.0f, 1.0f - cos_b * cos_b));
    float3 w = dist2 > 0.0f ? v * rsqrt(dist2) : (float3)(0.0f, 0.0f, 1.0f);
    /* the angle from the cone's axis to x, less the normals' spread and the box's */
    float cos_w = dot(w, node->axis.xyz);
    float sin_w = sqrt(fmax(0.0f, 1.0f - cos_w * cos_w));
    float cos_o = node->hi.w, sin_o = sqrt(fmax(0.0f, 1.0f - cos_o * cos_o));
    float cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    float sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    float cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if (cos_p <= node->axis.w)
        return 0.0f;
    /* pbrt-v4 keeps the distance from falling below half the box's diagonal */
    float importance = power * cos_p / fmax(dist2, sqrt(radius2));
    if (any(n != 0.0f)) {
        float cos_i = fabs(dot(w, n));
        float sin_i = sqrt(fmax(0.0f, 1.0f - cos_i * cos_i));
        importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    }
    return fmax(importance, 0.0f);
}

/* The threshold t of the first of two children of importance a and b: taken when 32 random
 * bits fall below t, with probability t / 2^32. A child of importance 0 is never taken, its
 * sibling always (t = 0 or 2^32). */
ulong split_threshold(float a, float b)
{
    if (!(b > 0.0f))
        return 1ul << 32;
    if (!(a > 0.0f))
        return 0ul;
    ulong t = (ulong)((double)(a / (a + b)) * 4294967296.0);
    return clamp(t, 1ul, (1ul << 32) - 1ul);
}

/* The probability that a split of threshold t takes the first child (or the second). */
float split_probability(ulong t, int second)
{
    return (float)(second ? (1ul << 32) - t : t) * 0x1.0p-32f;
}

/* Walks down from the root to a leaf, at every node taking a child by the split of their
 * importances at x; returns the leaf's light table entry (or -1 where no light reaches x) and
 * multiplies *pick by the probability of the walk. */
int pick_from_tree(const SceneData *sc, const global Light *root, float3 x, float3 n, Rng *rng,
                   float *pick)
{
    int node = 0;
    uint4 bits = (uint4)(0u);
    for (int level = 0; level < LIGHT_TREE_DEPTH; ++level) {
        int first = sc->light_nodes[node].child;
        if (first < 0)
            return sc->light_nodes[node].light;
        if ((level & 3) == 0)
            bits = next_bits4(rng);
        float a = node_importance(&sc->light_nodes[first], x, n);
        float b = node_importance(&sc->light_nodes[first + 1], x, n);
        if (!(a > 0.0f) && !(b > 0.0f))
            return -1;
        ulong t = split_threshold(a, b);
        int second = (ulong)bits.x >= t;
        *pick *= split_probability(t, second);
        node = first + second;
        bits = bits.yzwx;
    }
    return -1;
}

/* The probability with which pick_from_tree at x reaches leaf node `leaf`: the same splits, on
 * the way up from the leaf to the root. */
float tree_pick_probability(const SceneData *sc, int leaf, float3 x, float3 n)
{
    float pick = 1.0f;
    int node = leaf;
    for (int level = 0; level < LIGHT_TREE_DEPTH; ++level) {
        int parent = sc->light_nodes[node].parent;
        if (parent < 0)
            break;
        int first = sc->light_nodes[parent].child;
        ulong t = split_threshold(node_importance(&sc->light_nodes[first], x, n),
                                  node_importance(&sc->light_nodes[first + 1], x, n));
        pick *= split_probability(t, node != first);
        node = parent;
    }
    return pick;
}
