/* The environment as a light (kernels/environment.cl maps it): radiance from every direction,
 * infinitely far away.
 *
 *   prim -1; p0..p2 unused (the map and its sampling tables are the scene's env buffers)
 *
 * A constant colour is sampled by cosine about the shading normal (uniformly over the sphere at
 * a point inside a medium, which has none: n = 0), a map by its importance
 * (environment.cl: sample_environment_map). In a BDPT program a constant colour is sampled
 * uniformly everywhere: BDPT's weights give next-event estimation a share of every direction
 * towards the environment, the hemisphere behind a surface's normal too (light a transmitting
 * surface lets through), which only a density over the whole sphere draws (pbrt-v4's complete
 * densities for BDPT). */

/* The constant colour's sampling over the whole sphere at normal n. */
int uniform_environment(float3 n)
{
#ifdef BDPT
    return 1;
#elif defined(MEDIA)
    return all(n == 0.0f);
#else
    return 0;
#endif
}

float pdf_constant_environment(float3 n, float3 d)
{
    return uniform_environment(n) ? 1.0f / (4.0f * PI_F) : pdf_cosine_hemisphere(dot(n, d));
}

float3 sample_constant_environment(float3 n, float2 u)
{
    return uniform_environment(n) ? sample_uniform_sphere(u.x, u.y)
                                  : to_world(sample_cosine_hemisphere(u.x, u.y), n);
}

/* Density with which next-event estimation at a vertex of normal n samples direction d towards
 * the environment, once the environment is chosen: what MIS weighs an escaping path against. */
float pdf_environment(const SceneData *sc, const RenderParams *p, float3 n, float3 d)
{
    if (p->env_width == 1 && p->env_height == 1)
        return pdf_constant_environment(n, d);
    return pdf_environment_map(sc->env_marginal, sc->env_conditional, p, d);
}

/* A direction towards the environment from a vertex of normal n, drawn with pdf_environment. */
float3 sample_environment(const SceneData *sc, const RenderParams *p, float3 n, float2 u)
{
    return (p->env_width == 1 && p->env_height == 1)
               ? sample_constant_environment(n, u)
               : sample_environment_map(sc->env_marginal, sc->env_conditional, p, u.x, u.y);
}

int sample_environment_light(const SceneData *sc, const RenderParams *p, const global Light *l,
                             float3 x, float3 n, float2 u, LightSample *ls)
{
    ls->wi = sample_environment(sc, p, n, u);
    ls->pdf = pdf_environment(sc, p, n, ls->wi);
    ls->le = lookup_environment(sc->env, p, ls->wi);
    ls->flags = LIGHT_AT_INFINITY;
    return 1;
}

#ifdef BDPT
/* The density per solid angle of the directions d towards it (light travelling along -d) that
 * emit_environment_light draws: next-event estimation's, which a BDPT program draws over the
 * whole sphere whatever the normal (uniform_environment; pbrt-v4's ImageInfiniteLight and
 * UniformInfiniteLight PDF_Le). */
float pdf_environment_emission(const SceneData *sc, const RenderParams *p, float3 d)
{
    return pdf_environment(sc, p, (float3)(0.0f), d);
}

/* Light leaving the environment (kernels/bdpt.cl's light subpaths): a direction d towards it by
 * pdf_environment_emission, and light travelling along -d from the scene's disk across it
 * (leave_world_disk); le is the radiance from d. */
int emit_environment_light(const SceneData *sc, const RenderParams *p, const global Light *l, float4 u,
                           LightEmission *e)
{
    float3 d = sample_environment(sc, p, (float3)(0.0f), u.xy);
    e->pdf_dir = pdf_environment_emission(sc, p, d);
    e->le = lookup_environment(sc->env, p, d);
    e->delta = 0;
    leave_world_disk(p, -d, u.zw, e);
    return e->pdf_dir > 0.0f;
}
#endif
