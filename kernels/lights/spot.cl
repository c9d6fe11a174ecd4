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
