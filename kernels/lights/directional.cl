/* A directional light, a sun (app/lights/directional.py): irradiance E arriving from
 * infinitely far away, along one direction.
 *
 *   p0.xyz  the unit direction the light travels
 *   p1.xyz  irradiance E (W/m^2, rgb) on a surface facing it
 *
 * A delta light: the only direction towards it is sampled, and it delivers E. */

int sample_directional_light(const SceneData *sc, const RenderParams *p, const global Light *l,
                             float3 x, float3 n, float2 u, LightSample *ls)
{
    ls->wi = -l->p0.xyz;
    ls->pdf = 1.0f;
    ls->le = l->p1.xyz;
    ls->flags = LIGHT_DELTA | LIGHT_AT_INFINITY;
    return 1;
}
