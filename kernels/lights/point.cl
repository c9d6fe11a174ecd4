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

#ifdef BDPT
/* Light leaving a point light (kernels/bdpt.cl): every direction, uniformly (pbrt-v4's
 * PointLight::SampleLe); le is the intensity. */
int emit_point_light(const SceneData *sc, const global Light *l, float4 u, LightEmission *e)
{
    e->p = l->p0.xyz;
    e->n = (float3)(0.0f);
    e->d = sample_uniform_sphere(u.x, u.y);
    e->pdf_pos = 1.0f;
    e->pdf_dir = 1.0f / (4.0f * PI_F);
    e->le = l->p1.xyz;
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
