/* A material at a surface point: its textured parameters (app/textures; kernels/texture.cl)
 * looked up at the point's uv and written over the slots that hold their means, in a private
 * copy that the BSDFs read (MaterialRef, kernels/bsdf.cl). A program for a scene without
 * textures reads the scene's rows directly, as if none of this existed. */

#define SLOT_EMISSION 12

/* p with the binding's value written from component k on: a colour into .xyz, a number (the
 * texture's luminance) into component k. */
float4 with_slot(float4 p, int k, int width, float3 v)
{
    if (width == 3)
        return (float4)(v, p.w);
    float x = luminance(v);
    return (float4)(k == 0 ? x : p.x, k == 1 ? x : p.y, k == 2 ? x : p.z, k == 3 ? x : p.w);
}

/* Writes the textured parameters of material m (its bindings) at texture coordinates uv. */
void apply_textures(const SceneData *sc, Material *m, float2 uv)
{
    for (int i = m->textures;; ++i) {
        TextureBinding b = sc->bindings[i];
        int k = b.slot & 3;
        switch (b.slot >> 2) {      /* an opacity (slot 16) is the traversal's (kernels/masks.cl) */
        case 0: m->p0 = with_slot(m->p0, k, b.width, eval_texture(sc, b.texture, uv)); break;
        case 1: m->p1 = with_slot(m->p1, k, b.width, eval_texture(sc, b.texture, uv)); break;
        case 2: m->p2 = with_slot(m->p2, k, b.width, eval_texture(sc, b.texture, uv)); break;
        case 3: m->emission = with_slot(m->emission, k, b.width, eval_texture(sc, b.texture, uv)); break;
        }
        if (b.last)
            return;
    }
}

/* The material `row` at surface s (kernels/bvh.cl), whose uv is found only if a texture needs
 * it; a normal or bump map perturbs s's shading normal, before the side it is seen from turns it
 * (kernels/normal_maps.cl: perturb_normal, face_perturbed_normal). */
Material shade_material(const SceneData *sc, const global Material *row, Surface *s)
{
    Material m = *row;
#ifdef NORMAL_MAPS
    s->ns_unperturbed = s->ns;
    s->terminator = 0.0f;
#endif
    if (m.textures >= 0) {
        float2 uv = surface_uv(sc, s->prim, s->b, s->p);
        apply_textures(sc, &m, uv);
#ifdef NORMAL_MAPS
        perturb_normal(sc, row, uv, s);
#endif
    }
    return m;
}

/* The texture bound to the emission of material `row`, or -1. */
int emission_texture(const SceneData *sc, const global Material *row)
{
    for (int i = row->textures; i >= 0; ++i) {
        TextureBinding b = sc->bindings[i];
        if (b.slot == SLOT_EMISSION)
            return b.texture;
        if (b.last)
            break;
    }
    return -1;
}

/* The radiance a textured material emits at uv: its emission, or its emission texture there. */
float3 emission_at(const SceneData *sc, const global Material *row, float2 uv)
{
    int t = emission_texture(sc, row);
    return t < 0 ? row->emission.xyz : eval_texture(sc, t, uv);
}

/* The radiance material `row` emits at surface s: its uv is found only where the emission is a
 * texture, and no other texture is looked up. */
float3 surface_emission(const SceneData *sc, const global Material *row, const Surface *s)
{
    int t = emission_texture(sc, row);
    return t < 0 ? row->emission.xyz : eval_texture(sc, t, surface_uv(sc, s->prim, s->b, s->p));
}
