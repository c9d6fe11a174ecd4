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
