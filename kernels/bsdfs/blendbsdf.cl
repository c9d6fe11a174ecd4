/* blendbsdf: two materials mixed, f = (1 - weight) f_1 + weight f_2 (Mitsuba 3's `blendbsdf`;
 * pbrt-v4's `mix`, whose amount is the weight). Rather than evaluating both, a hit takes one of
 * them, the second with probability weight, as pbrt-v4's MixMaterial does: the path's estimate
 * is the mixture's in expectation, and light sampling and BSDF sampling at the vertex see one
 * material, so that their MIS weights sum to 1 as for any other. The choice is a hash of the
 * hit point and the direction it is seen from (pbrt's HashFloat), so that it needs no random
 * number of the path's and is the same wherever a vertex is shaded (kernels/aovs.cl too).
 * The components are rows of the material table of their own, which carry the blend's
 * emission, sides and shading maps (app/materials/table.py); blends may nest, at most
 * MAX_BLEND_DEPTH deep (app/materials/blend.py). Compiled in for scenes with a blend (BLEND).
 * Its weight and its components' rows are read through BLENDBSDF_WEIGHT, _FIRST and _SECOND,
 * generated from their slots on the host (app/materials/blend.py). */

#define MAX_BLEND_DEPTH 8

/* The component of blend `row` (or of the blends it nests) that surface s takes, seen from wo;
 * any other row is its own. */
const global Material *choose_component(const SceneData *sc, const global Material *row,
                                        const Surface *s, float3 wo)
{
    for (uint level = 0; row->type == BSDF_BLENDBSDF && level < MAX_BLEND_DEPTH; ++level) {
        float weight = BLENDBSDF_WEIGHT(row);
#ifdef TEXTURES
        if (row->textures >= 0) {
            Material shaded = *row;
            apply_textures(sc, &shaded, surface_uv(sc, s->prim, s->b, s->p));
            weight = BLENDBSDF_WEIGHT(&shaded);
        }
#endif
        uint4 h = pcg4d(as_uint4((float4)(s->p, wo.x)) ^ (uint4)(as_uint(wo.y), as_uint(wo.z), level, 0x9e3779b9u));
        float u = (float)(h.x >> 8) * 0x1.0p-24f;
        row = &sc->materials[(int)(u < weight ? BLENDBSDF_SECOND(row) : BLENDBSDF_FIRST(row))];
    }
    return row;
}
