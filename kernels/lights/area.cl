/* An area light: an emissive primitive (a sphere or a triangle of the scene), whose material's
 * emission (a colour or a texture, kernels/shading.cl) leaves its front side, or both sides of a
 * triangle whose material has MATERIAL_EMITS_BACK.
 *
 *   prim   the primitive; p0..p2 unused
 *
 * A sphere is sampled over the cone it subtends from the shading point, a triangle by area. */

/* Whether primitive `prim` emits from its back as well as its front. */
int emits_back(const SceneData *sc, int prim)
{
    return sc->materials[sc->prim_material[prim]].flags & MATERIAL_EMITS_BACK;
}

/* Density (per solid angle, the light's choice included) with which next-event estimation at x
 * (shading normal n) samples point y on emissive primitive `prim`: what MIS weighs a path that
 * hit it against. Through a light tree, the choice depends on x and n, from the light's leaf
 * up. */
float pdf_light(const SceneData *sc, int prim, float3 x, float3 n, float3 y)
{
    float pick = sc->light_pick[prim];
#ifdef LIGHT_TREE
    if (HAS_LIGHT_TREE(sc))
        pick *= tree_pick_probability(sc, sc->light_leaf[prim], x, n);
#endif
#ifndef NO_TRIANGLES
    if (prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[prim - sc->num_spheres];
#ifdef SHAPES
        if (SHAPE_KIND(tri))
            return pick * pdf_analytic_solid_angle(SHAPE_KIND(tri), SHAPE_ROWS(sc, tri), x, y, emits_back(sc, prim));
#endif
        return pick * pdf_triangle_solid_angle(tri, x, y, emits_back(sc, prim));
    }
#endif
    return pick * pdf_sphere_cone(sc->spheres[prim], x);
}

/* The emitter's radiance at point y of primitive `prim`, b its barycentric weights on a triangle
 * (looked up there where the emission is a texture). */
float3 area_light_radiance(const SceneData *sc, int prim, float3 y, float2 b)
{
    const global Material *m = &sc->materials[sc->prim_material[prim]];
#ifdef TEXTURES
    if (m->textures < 0)
        return m->emission.xyz;
    float2 uv = surface_uv(sc, prim, b, y);
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

int sample_area_light(const SceneData *sc, const RenderParams *p, const global Light *l, float3 x,
                      float3 n, float2 u, LightSample *ls)
{
    float2 b = (float2)(0.0f);
#ifndef NO_TRIANGLES
    if (l->prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[l->prim - sc->num_spheres];
#ifdef SHAPES
        if (SHAPE_KIND(tri)) {
            const global float4 *f = SHAPE_ROWS(sc, tri);
            float3 n, error;
            float pdf_area;
            ls->y = sample_analytic(SHAPE_KIND(tri), f, u, &b, &n, &error, &pdf_area);
            float3 w = ls->y - x;
            float dist2 = dot(w, w);
            ls->wi = w * rsqrt(dist2);
            float cos_l = -dot(n, ls->wi);
            if (emits_back(sc, l->prim))
                cos_l = fabs(cos_l);
            ls->pdf = cos_l > 0.0f ? pdf_area * dist2 / cos_l : 0.0f;
            ls->le = area_light_radiance(sc, l->prim, ls->y, b);
            return ls->pdf > 0.0f;
        }
#endif
        ls->y = sample_triangle_area(tri, u.x, u.y, &b);
        ls->wi = unit(ls->y - x);
        ls->pdf = pdf_triangle_solid_angle(tri, x, ls->y, emits_back(sc, l->prim));
        ls->le = area_light_radiance(sc, l->prim, ls->y, b);
        return 1;
    }
#endif
    Sphere s = sc->spheres[l->prim];
    ls->wi = sample_sphere_cone(s, x, u.x, u.y);
    ls->pdf = pdf_sphere_cone(s, x);
    /* the point the direction meets; on the cone's rim, where rounding may miss the sphere, the
       tangent point */
    float t = intersect_range_sphere(s, x, ls->wi, INFINITY);
    ls->y = x + (isinf(t) ? dot(s.xyz - x, ls->wi) : t) * ls->wi;
    ls->le = area_light_radiance(sc, l->prim, ls->y, b);
    return 1;
}

#ifdef BDPT
/* Light leaving an area light (kernels/bdpt.cl's light subpaths; pbrt-v4's DiffuseAreaLight::
 * SampleLe): a point uniform over the primitive's area (a sphere's whole surface, whose back
 * half faces away from any point that sees it), and a cosine-weighted direction about its
 * normal, on its front or, for an emitter of both sides, on either with probability 1/2. */
int emit_area_light(const SceneData *sc, const RenderParams *p, const global Light *l, float4 u, LightEmission *e)
{
    float2 b = (float2)(0.0f);
    float3 d = sample_cosine_hemisphere(u.z, u.w);
    int two_sided = emits_back(sc, l->prim);
    float side = 1.0f;
    if (two_sided) {
        /* the first uniform picks the side and is stretched back onto [0, 1) for the point */
        side = u.x < 0.5f ? 1.0f : -1.0f;
        u.x = u.x < 0.5f ? 2.0f * u.x : 2.0f * u.x - 1.0f;
    }
#ifndef NO_TRIANGLES
    if (l->prim >= sc->num_spheres) {
        const global Triangle *tri = &sc->triangles[l->prim - sc->num_spheres];
#ifdef SHAPES
        if (SHAPE_KIND(tri)) {
            float3 error;
            e->p = sample_analytic(SHAPE_KIND(tri), SHAPE_ROWS(sc, tri), u.xy, &b, &e->n, &error, &e->pdf_pos);
            e->n *= side;
            e->offset = error_offset(e->n, error);
        } else {
#endif
        e->p = sample_triangle_area(tri, u.x, u.y, &b);
        e->n = side * triangle_normal(tri);
        e->pdf_pos = 1.0f / triangle_area(tri);
        /* the point's rounding error is within gamma(7) of the corners' magnitudes (pbrt-v4
           eq. 6.29, |b_i v_i| <= |v_i|) */
        e->offset = error_offset(e->n, gamma_bound(7) * (fabs(tri->v0.xyz) + fabs(tri->v1.xyz) + fabs(tri->v2.xyz)));
#ifdef SHAPES
        }
#endif
    } else
#endif
    {
        Sphere s = sc->spheres[l->prim];
        e->n = sample_uniform_sphere(u.x, u.y);
        e->p = s.xyz + s.w * e->n;
        e->pdf_pos = 1.0f / (4.0f * PI_F * s.w * s.w);
        e->offset = gamma_bound(8) * (dot(fabs(s.xyz), fabs(e->n)) + s.w);
    }
    e->d = to_world(d, e->n);
    e->pdf_dir = pdf_cosine_hemisphere(d.z) * (two_sided ? 0.5f : 1.0f);
    e->le = area_light_radiance(sc, l->prim, e->p, b);
    e->prim = l->prim;
    e->delta = 0;
    return e->pdf_dir > 0.0f;
}

/* The density per solid angle with which emit_area_light leaves point y of primitive `prim`
 * (normal n, on its front) in direction w. */
float pdf_area_emission(const SceneData *sc, int prim, float3 n, float3 w)
{
    float c = dot(n, w);
    if (emits_back(sc, prim))
        return 0.5f * fabs(c) / PI_F;
    return c > 0.0f ? c / PI_F : 0.0f;
}
#endif
