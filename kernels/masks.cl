/* Alpha masks (Mitsuba 3's `mask` BSDF, pbrt-v4's `alpha`): a material's opacity, a number or a
 * texture in [0, 1], is the probability that a ray meets its surface at a point. Traversal itself
 * decides (kernels/bvh.cl), for camera rays, bounces and shadow rays alike, so that a leaf's cut-out
 * casts the shadow of its shape and nothing is spent on the paths through the holes: a hit is
 * skipped when a uniform number hashed from the hit point, the ray's direction and the
 * primitive is not below the opacity (pbrt-v4's stochastic alpha test hashes the ray that
 * reaches the point the same way). The same crossing of a primitive is decided the same way
 * each time it is tested (it may straddle several leaves); a sphere's two crossings, at
 * different points, independently.
 * Compiled in only for scenes with a material that has an opacity (ALPHA_MASKS). */

#define SLOT_OPACITY 16      /* the opacity's binding slot (app/materials/table.py) */

/* The opacity of material m at uv: its opacity binding's value (the texture's luminance), or 1. */
DISPATCH float opacity_at(const SceneData *sc, const global Material *m, float2 uv)
{
    for (int i = m->textures;; ++i) {
        TextureBinding b = sc->bindings[i];
        if (b.slot == SLOT_OPACITY)
            return luminance(eval_texture(sc, b.texture, uv));
        if (b.last)
            return 1.0f;
    }
}

/* Whether the ray along d passes through primitive prim's surface at point p (a triangle's
 * barycentric weights b). */
DISPATCH int masked_out(const SceneData *sc, int prim, float2 b, float3 p, float3 d)
{
    const global Material *m = &sc->materials[sc->prim_material[prim]];
    if (!(m->flags & MATERIAL_MASKED))
        return 0;
    float2 uv;
#ifndef NO_TRIANGLES
    if (prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[prim - sc->num_spheres];
#ifdef SHAPES
        uv = SHAPE_KIND(tri) ? analytic_texture_uv(SHAPE_ROWS(sc, tri), b) : triangle_uv(tri, sc->uvs, b.x, b.y);
#else
        uv = triangle_uv(tri, sc->uvs, b.x, b.y);
#endif
    } else
#endif
        uv = range_sphere_uv(sc->spheres[prim], p);
    float opacity = opacity_at(sc, m, uv);
    if (opacity >= 1.0f)
        return 0;
    uint4 key = (uint4)(as_uint(p.x) ^ as_uint(d.z), as_uint(p.y) ^ as_uint(d.x),
                        as_uint(p.z) ^ as_uint(d.y), (uint)prim);
    return to_uniform4(pcg4d(key)).x >= opacity;
}
