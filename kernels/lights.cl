/* Light sampling for next-event estimation. Every emitter (emissive spheres and triangles, and
 * the environment) is one entry of one light table, chosen in proportion to its power through
 * an alias table (app/lights.py); then a direction towards it is sampled: over the cone a sphere
 * subtends, by area on a triangle, by importance over the environment map. */

/* Power heuristic with beta = 2 (Veach, "Robust Monte Carlo Methods for Light Transport
 * Simulation", 1997, section 9.2.4): the weight of the technique with density a. Written as
 * 1 / (1 + (b / a)^2), so that densities whose squares overflow float32 (a Phong lobe of
 * exponent 1e8 has a density of 1.6e7) give 0 or 1, never inf / inf. */
float mis_weight(float a, float b)
{
    float r = b / a;
    return a > 0.0f ? 1.0f / (1.0f + r * r) : 0.0f;
}

/* Walker's alias method: a bin chosen uniformly, then kept or replaced by its alias, picks a
 * light in proportion to its power. The bin comes from all 32 bits of one hash word, as
 * floor(bin_bits * count / 2^32) (each bin's probability is 1/count to within count / 2^32
 * relative), and the keep test from all 32 bits of another, against the threshold the host
 * stored (app/lights.py keep_threshold). Drawing both from one float, as before, left the keep
 * test 24 - log2(count) bits, which skewed the choice by up to 2x at 2^17 lights. */
int pick_light(const global Light *lights, int count, uint bin_bits, uint keep_bits)
{
    int i = (int)mul_hi(bin_bits, (uint)count);
    return keep_bits < lights[i].keep ? i : lights[i].alias;
}

/* Density with which next-event estimation at a vertex of normal n samples direction d towards
 * the environment, once the environment is chosen: cosine-weighted for a constant colour, the
 * map's distribution otherwise. */
float pdf_environment(const SceneData *sc, const RenderParams *p, float3 n, float3 d)
{
    if (p->env_width == 1 && p->env_height == 1)
        return pdf_cosine_hemisphere(dot(n, d));
    return pdf_environment_map(sc->env_marginal, sc->env_conditional, p, d);
}

/* Density (per solid angle, the light's choice included) with which next-event estimation at x
 * samples point y on emissive primitive `prim`. */
float pdf_light(const SceneData *sc, int prim, float3 x, float3 y)
{
    float pick = sc->light_pick[prim];
#ifndef NO_TRIANGLES
    if (prim >= sc->num_spheres)
        return pick * pdf_triangle_solid_angle(&sc->triangles[prim - sc->num_spheres], x, y);
#endif
    return pick * pdf_sphere_cone(sc->spheres[prim], x);
}

typedef struct {
    float3 wi;       /* unit direction from the shading point towards the light */
    float pdf;       /* its density per solid angle, the light's choice included */
    float3 y;        /* the point on the light (unused for the environment) */
    int prim;        /* the emitter: a primitive, or -1 for the environment */
    float2 b;        /* y's barycentric weights on a triangle (for its texture coordinates) */
} LightSample;

/* Draws a light and a direction towards it from point x of shading normal n, from four hash
 * words: the light from r.w and r.x, the direction from r.y and r.z. */
LightSample sample_light(const SceneData *sc, const RenderParams *p, float3 x, float3 n, uint4 r)
{
    float4 u = to_uniform4(r);
    Light light = sc->lights[pick_light(sc->lights, p->num_lights, r.w, r.x)];
    LightSample ls = {(float3)(0.0f), 0.0f, (float3)(0.0f), light.prim, (float2)(0.0f)};
    if (light.prim < 0) {
        ls.wi = (p->env_width == 1 && p->env_height == 1)
                    ? to_world(sample_cosine_hemisphere(u.y, u.z), n)
                    : sample_environment_map(sc->env_marginal, sc->env_conditional, p, u.y, u.z);
        ls.pdf = light.pick * pdf_environment(sc, p, n, ls.wi);
    }
#ifndef NO_TRIANGLES
    else if (light.prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[light.prim - sc->num_spheres];
        ls.y = sample_triangle_area(tri, u.y, u.z, &ls.b);
        ls.wi = unit(ls.y - x);
        ls.pdf = light.pick * pdf_triangle_solid_angle(tri, x, ls.y);
    }
#endif
    else {
        Sphere s = sc->spheres[light.prim];
        ls.wi = sample_sphere_cone(s, x, u.y, u.z);
        ls.pdf = light.pick * pdf_sphere_cone(s, x);
        /* the point the direction meets; on the cone's rim, where rounding may miss the
         * sphere, the tangent point */
        float t = intersect_sphere(s, x, ls.wi, INFINITY);
        ls.y = x + (isinf(t) ? dot(s.xyz - x, ls.wi) : t) * ls.wi;
    }
    return ls;
}

/* The radiance arriving from a light sample's point (its emitter's, looked up at the point
 * where the emission is a texture), or the environment's along its direction. */
float3 light_radiance(const SceneData *sc, const RenderParams *p, const LightSample *ls)
{
    if (ls->prim < 0)
        return lookup_environment(sc->env, p, ls->wi);
    const global Material *m = &sc->materials[sc->prim_material[ls->prim]];
#ifdef TEXTURES
    if (m->textures < 0)
        return m->emission.xyz;
    float2 uv = surface_uv(sc, ls->prim, ls->b, ls->y);
    float3 le = emission_at(sc, m, uv);
#ifdef ALPHA_MASKS
    /* a masked emitter is there with probability `opacity` where paths meet it; light sampling
       finds its holes too, so it weighs the radiance by that probability */
    if (m->flags & MATERIAL_MASKED)
        le *= opacity_at(sc, m, uv);
#endif
    return le;
#else
    return m->emission.xyz;
#endif
}
