/* A spot light (app/lights/spot.py): radiant intensity I from a point, along an axis, scaled
 * by a falloff of the angle theta from the axis: 1 within the beam, 0 beyond the cutoff, and
 * between them either Mitsuba 3's `spot` (linear in theta: (cutoff - theta) / (cutoff - beam))
 * or pbrt-v4's `spot` (smoothstep(cos cutoff, cos beam, cos theta)). Its values are read through
 * SPOT_LIGHT_<SLOT>, generated from their slots on the host (app/lights/spot.py).
 *
 * A delta light: the only direction towards it is sampled, and it delivers I falloff / r^2. */

/* The falloff at cos_theta from the axis. */
float spot_falloff(const global Light *l, float cos_theta)
{
    float cos_cutoff = SPOT_LIGHT_COS_CUTOFF(l), cos_beam = SPOT_LIGHT_COS_BEAM(l);
    if (cos_theta <= cos_cutoff)
        return 0.0f;
    if (cos_theta >= cos_beam)
        return 1.0f;
    if (SPOT_LIGHT_FALLOFF_RATE(l) < 0.0f) {
        float t = (cos_theta - cos_cutoff) / (cos_beam - cos_cutoff);
        return t * t * (3.0f - 2.0f * t);
    }
    return (acos(cos_cutoff) - acos(cos_theta)) * SPOT_LIGHT_FALLOFF_RATE(l);
}

int sample_spot_light(const SceneData *sc, const RenderParams *p, const global Light *l, float3 x,
                      float3 n, float2 u, LightSample *ls)
{
    float r2;
    if (!aim_at_position(SPOT_LIGHT_POSITION(l), x, ls, &r2))
        return 0;
    ls->le = SPOT_LIGHT_INTENSITY(l) * (spot_falloff(l, dot(-ls->wi, SPOT_LIGHT_DIRECTION(l))) / r2);
    return 1;
}

#ifdef BDPT
/* The density per solid angle with which emit_spot_light leaves in direction w. */
float pdf_spot_emission(const global Light *l, float3 w)
{
    float cos_cutoff = SPOT_LIGHT_COS_CUTOFF(l);
    return dot(w, SPOT_LIGHT_DIRECTION(l)) > cos_cutoff ? 1.0f / (2.0f * PI_F * (1.0f - cos_cutoff)) : 0.0f;
}

/* Light leaving a spot light (kernels/bdpt.cl): directions uniform in the cone of its cutoff
 * (pbrt-v4's SpotLight::SampleLe); le is the intensity times the falloff. */
int emit_spot_light(const SceneData *sc, const RenderParams *p, const global Light *l, float4 u, LightEmission *e)
{
    float cos_cutoff = SPOT_LIGHT_COS_CUTOFF(l);
    float cos_t = 1.0f - u.x * (1.0f - cos_cutoff);
    float sin_t = sqrt(fmax(0.0f, 1.0f - cos_t * cos_t));
    e->p = SPOT_LIGHT_POSITION(l);
    e->n = (float3)(0.0f);
    e->d = to_world((float3)(COS_TURNS(u.y) * sin_t, SIN_TURNS(u.y) * sin_t, cos_t), SPOT_LIGHT_DIRECTION(l));
    e->pdf_pos = 1.0f;
    e->pdf_dir = pdf_spot_emission(l, e->d);
    e->le = SPOT_LIGHT_INTENSITY(l) * spot_falloff(l, cos_t);
    e->offset = 0.0f;
    e->prim = -1;
    e->delta = 1;
    return e->pdf_dir > 0.0f;
}
#endif
