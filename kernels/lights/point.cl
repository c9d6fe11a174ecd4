/* A point light (app/lights/point.py): radiant intensity I in every direction from a point, its
 * position and I read through POINT_LIGHT_POSITION and _INTENSITY, generated from their slots
 * on the host.
 *
 * A delta light: the only direction towards it is sampled, and it delivers I / r^2. */

int sample_point_light(const SceneData *sc, const RenderParams *p, const global Light *l, float3 x,
                       float3 n, float2 u, LightSample *ls)
{
    float r2;
    if (!aim_at_position(POINT_LIGHT_POSITION(l), x, ls, &r2))
        return 0;
    ls->le = POINT_LIGHT_INTENSITY(l) / r2;
    return 1;
}

#ifdef BDPT
/* Light leaving a point light (kernels/bdpt.cl): every direction, uniformly (pbrt-v4's
 * PointLight::SampleLe); le is the intensity. */
int emit_point_light(const SceneData *sc, const RenderParams *p, const global Light *l, float4 u, LightEmission *e)
{
    e->p = POINT_LIGHT_POSITION(l);
    e->n = (float3)(0.0f);
    e->d = sample_uniform_sphere(u.x, u.y);
    e->pdf_pos = 1.0f;
    e->pdf_dir = 1.0f / (4.0f * PI_F);
    e->le = POINT_LIGHT_INTENSITY(l);
    e->offset = 0.0f;
    e->prim = -1;
    e->delta = 1;
    return 1;
}

/* The density per solid angle with which emit_point_light leaves in direction w. */
float pdf_point_emission(const global Light *l, float3 w)
{
    return 1.0f / (4.0f * PI_F);
}
#endif
