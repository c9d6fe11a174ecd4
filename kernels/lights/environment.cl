/* The environment as a light (kernels/environment.cl maps it): radiance from every direction,
 * infinitely far away.
 *
 *   prim -1; p0..p2 unused (the map and its sampling tables are the scene's env buffers)
 *
 * A constant colour is sampled by cosine about the shading normal (uniformly over the sphere at
 * a point inside a medium, which has none: n = 0), a map by its importance
 * (environment.cl: sample_environment_map). */

float pdf_constant_environment(float3 n, float3 d)
{
#ifdef MEDIA
    if (all(n == 0.0f))
        return 1.0f / (4.0f * PI_F);
#endif
    return pdf_cosine_hemisphere(dot(n, d));
}

float3 sample_constant_environment(float3 n, float2 u)
{
#ifdef MEDIA
    if (all(n == 0.0f))
        return sample_uniform_sphere(u.x, u.y);
#endif
    return to_world(sample_cosine_hemisphere(u.x, u.y), n);
}

/* Density with which next-event estimation at a vertex of normal n samples direction d towards
 * the environment, once the environment is chosen: what MIS weighs an escaping path against. */
float pdf_environment(const SceneData *sc, const RenderParams *p, float3 n, float3 d)
{
    if (p->env_width == 1 && p->env_height == 1)
        return pdf_constant_environment(n, d);
    return pdf_environment_map(sc->env_marginal, sc->env_conditional, p, d);
}

int sample_environment_light(const SceneData *sc, const RenderParams *p, const global Light *l,
                             float3 x, float3 n, float2 u, LightSample *ls)
{
    ls->wi = (p->env_width == 1 && p->env_height == 1)
                 ? sample_constant_environment(n, u)
                 : sample_environment_map(sc->env_marginal, sc->env_conditional, p, u.x, u.y);
    ls->pdf = pdf_environment(sc, p, n, ls->wi);
    ls->le = lookup_environment(sc->env, p, ls->wi);
    ls->flags = LIGHT_AT_INFINITY;
    return 1;
}
