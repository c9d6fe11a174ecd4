/* A spot light (app/lights/spot.py): radiant intensity I from a point, along an axis, scaled
 * by a falloff of the angle theta from the axis: 1 within the beam, 0 beyond the cutoff, and
 * between them either Mitsuba 3's `spot` (linear in theta: (cutoff - theta) / (cutoff - beam))
 * or pbrt-v4's `spot` (smoothstep(cos cutoff, cos beam, cos theta)).
 *
 *   p0.xyz  position           p0.w  cos(cutoff angle)
 *   p1.xyz  intensity I        p1.w  cos(beam width)
 *   p2.xyz  unit axis          p2.w  1 / (cutoff - beam) in radians for the linear falloff
 *                                    (0: no band between them), -1 for the smoothstep
 *
 * A delta light: the only direction towards it is sampled, and it delivers I falloff / r^2. */

/* The falloff at cos_theta from the axis. */
float spot_falloff(const global Light *l, float cos_theta)
{
    float cos_cutoff = l->p0.w, cos_beam = l->p1.w;
    if (cos_theta <= cos_cutoff)
        return 0.0f;
    if (cos_theta >= cos_beam)
        return 1.0f;
    if (l->p2.w < 0.0f) {
        float t = (cos_theta - cos_cutoff) / (cos_beam - cos_cutoff);
        return t * t * (3.0f - 2.0f * t);
    }
    return (acos(cos_cutoff) - acos(cos_theta)) * l->p2.w;
}

int sample_spot_light(const SceneData *sc, const RenderParams *p, const global Light *l, float3 x,
                      float3 n, float2 u, LightSample *ls)
{
    float r2;
    if (!aim_at_position(l->p0.xyz, x, ls, &r2))
        return 0;
    ls->le = l->p1.xyz * (spot_falloff(l, dot(-ls->wi, l->p2.xyz)) / r2);
    return 1;
}

#ifdef BDPT
/* The density per solid angle with which emit_spot_light leaves in direction w. */
float pdf_spot_emission(const global Light *l, float3 w)
{
    float cos_cutoff = l->p0.w;
    return dot(w, l->p2.xyz) > cos_cutoff ? 1.0f / (2.0f * PI_F * (1.0f - cos_cutoff)) : 0.0f;
}

/* Light leaving a spot light (kernels/bdpt.cl): directions uniform in the cone of its cutoff
 * (pbrt-v4's SpotLight::SampleLe); le is the intensity times the falloff. */
int emit_spot_light(const SceneData *sc, const global Light *l, float4 u, LightEmission *e)
{
    float cos_cutoff = l->p0.w;
    float cos_t = 1.0f - u.x * (1.0f - cos_cutoff);
    float sin_t = sqrt(fmax(0.0f, 1.0f - cos_t * cos_t));
    e->p = l->p0.xyz;
    e->n = (float3)(0.0f);
    e->d = to_world((float3)(COS_TURNS(u.y) * sin_t, SIN_TURNS(u.y) * sin_t, cos_t), l->p2.xyz);
    e->pdf_pos = 1.0f;
    e->pdf_dir = pdf_spot_emission(l, e->d);
    e->le = l->p1.xyz * spot_falloff(l, cos_t);
    e->offset = 0.0f;
    e->prim = -1;
    e->delta = 1;
    return e->pdf_dir > 0.0f;
}
#endif
