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

#ifdef BDPT
/* The density per solid angle with which emit_projection_light leaves in world direction w: a
 * point uniform on the screen, of area A = 4 half.x half.y tan^2(fov / 2) at distance 1 in the
 * light's space, seen at cos theta = w'.z: 1 / (A cos^3 theta) inside the frustum, 0 outside
 * (pbrt-v4's ProjectionLight::PDF_Le). */
float pdf_projection_emission(const global Light *l, float3 w)
{
    float3 v = to_light_space(PROJECTION_LIGHT_ROTATION(l), w);
    if (v.z < PROJECTION_HITHER)
        return 0.0f;
    float tan_half = PROJECTION_LIGHT_TAN_HALF_FOV(l);
    float2 half_extent = PROJECTION_LIGHT_HALF_EXTENT(l);
    float2 s = (float2)(v.x, -v.y) / (v.z * tan_half);
    if (fabs(s.x) > half_extent.x || fabs(s.y) > half_extent.y)
        return 0.0f;
    float area = 4.0f * half_extent.x * half_extent.y * tan_half * tan_half;
    return 1.0f / (area * v.z * v.z * v.z);
}

/* Light leaving a projection light (kernels/bdpt.cl): through a point uniform on its screen
 * (pbrt-v4's ProjectionLight::SampleLe); le is the intensity along it. */
int emit_projection_light(const SceneData *sc, const RenderParams *p, const global Light *l, float4 u,
                          LightEmission *e)
{
#ifdef TEXTURES
    float tan_half = PROJECTION_LIGHT_TAN_HALF_FOV(l);
    float2 half_extent = PROJECTION_LIGHT_HALF_EXTENT(l);
    float2 s = (2.0f * u.xy - 1.0f) * half_extent;
    float4 q = PROJECTION_LIGHT_ROTATION(l);
    /* the light's space to the world's: the rotation by q, to_light_space's by its conjugate */
    float3 v = unit((float3)(s.x * tan_half, -s.y * tan_half, 1.0f));
    e->p = PROJECTION_LIGHT_POSITION(l);
    e->n = (float3)(0.0f);
    e->d = to_light_space((float4)(-q.xyz, q.w), v);
    e->pdf_pos = 1.0f;
    e->pdf_dir = pdf_projection_emission(l, e->d);
    e->le = eval_texture(sc, (int)PROJECTION_LIGHT_SLIDE(l), (s + half_extent) / (2.0f * half_extent))
            * PROJECTION_LIGHT_SCALE(l);
    e->offset = 0.0f;
    e->prim = -1;
    e->delta = 1;
    return e->pdf_dir > 0.0f;
#else
    return 0;
#endif
}
#endif
