/* A directional light, a sun (app/lights/directional.py): irradiance E arriving from
 * infinitely far away, along one direction: DIRECTIONAL_LIGHT_DIRECTION, the way it travels, and
 * _IRRADIANCE, E on a surface facing it, generated from their slots on the host.
 *
 * A delta light: the only direction towards it is sampled, and it delivers E. */

int sample_directional_light(const SceneData *sc, const RenderParams *p, const global Light *l,
                             float3 x, float3 n, float2 u, LightSample *ls)
{
    ls->wi = -DIRECTIONAL_LIGHT_DIRECTION(l);
    ls->pdf = 1.0f;
    ls->le = DIRECTIONAL_LIGHT_IRRADIANCE(l);
    ls->flags = LIGHT_DELTA | LIGHT_AT_INFINITY;
    return 1;
}

#ifdef BDPT
/* Light leaving a directional light (kernels/bdpt.cl): along its one direction from the scene's
 * disk across it (leave_world_disk; pbrt-v4's DistantLight::SampleLe); le is the irradiance E,
 * the direction's density 1 (a delta). */
int emit_directional_light(const SceneData *sc, const RenderParams *p, const global Light *l, float4 u,
                           LightEmission *e)
{
    e->pdf_dir = 1.0f;
    e->le = DIRECTIONAL_LIGHT_IRRADIANCE(l);
    e->delta = 1;
    leave_world_disk(p, DIRECTIONAL_LIGHT_DIRECTION(l), u.xy, e);
    return 1;
}
#endif
