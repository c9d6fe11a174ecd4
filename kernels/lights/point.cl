/* A point light (app/lights/point.py): radiant intensity I in every direction from a point.
 *
 *   p0.xyz  position
 *   p1.xyz  intensity I (W/sr, rgb)
 *
 * A delta light: the only direction towards it is sampled, and it delivers I / r^2. */

int sample_point_light(const SceneData *sc, const RenderParams *p, const global Light *l, float3 x,
                       float3 n, float2 u, LightSample *ls)
{
    float r2;
    if (!aim_at_position(l->p0.xyz, x, ls, &r2))
        return 0;
    ls->le = l->p1.xyz / r2;
    return 1;
}
