/* A projection light (app/lights/projection.py, pbrt-v4's `projection`): a point light that
 * projects an image through a perspective frustum. In the light's space, its y turned round (as
 * pbrt-v4 flips it), a direction w with w.z above the hither plane meets the screen at
 * s = w.xy / (w.z tan(fov / 2)); inside the screen's half extents the radiant intensity is scale
 * times the image's nearest texel at (s + half) / (2 half), outside none.
 * Its values are read through PROJECTION_LIGHT_<SLOT>, generated from their slots on the host
 * (app/lights/projection.py).
 *
 * A delta light: the only direction towards it is sampled, and it delivers I(w) / r^2. */

#define PROJECTION_HITHER 1e-3f     /* pbrt-v4's ProjectionLight: no light below it */

int sample_projection_light(const SceneData *sc, const RenderParams *p, const global Light *l, float3 x,
                            float3 n, float2 u, LightSample *ls)
{
#ifdef TEXTURES
    float r2;
    float3 w;
    if (!aim_from_frame(PROJECTION_LIGHT_POSITION(l), PROJECTION_LIGHT_ROTATION(l), x, ls, &r2, &w)
        || w.z < PROJECTION_HITHER)
        return 0;
    float2 half_extent = PROJECTION_LIGHT_HALF_EXTENT(l);
    float2 s = (float2)(w.x, -w.y) / (w.z * PROJECTION_LIGHT_TAN_HALF_FOV(l));
    if (fabs(s.x) > half_extent.x || fabs(s.y) > half_extent.y)
        return 0;
    ls->le = eval_texture(sc, (int)PROJECTION_LIGHT_SLIDE(l), (s + half_extent) / (2.0f * half_extent)) * (PROJECTION_LIGHT_SCALE(l) / r2);
    return 1;
#else
    return 0;        /* a program without textures has no projection light's image */
#endif
}
