/* A goniometric light (app/lights/goniometric.py, pbrt-v4's `goniometric`): a point light of
 * radiant intensity I(w) = I image(s(w')), w' the direction w in the light's own space with y
 * and z swapped (the map's pole is the light's +y), s the equal-area mapping of the sphere onto
 * the square, the image (its channels' mean) looked up at the nearest texel.
 * Its values are read through GONIOMETRIC_LIGHT_<SLOT>, generated from their slots on the host
 * (app/lights/goniometric.py).
 *
 * A delta light: the only direction towards it is sampled, and it delivers I(w) / r^2. */

/* Clarberg's equal-area mapping of a unit direction onto [0, 1]^2 (pbrt-v4's
 * EqualAreaSphereToSquare, src/pbrt/util/math.cpp; app/scene/pbrt/equal_area.py:
 * sphere_to_square): +z at the centre, -z at the corners, the image's first row at v = 0. */
float2 equal_area_square(float3 d)
{
    float x = fabs(d.x), y = fabs(d.y);
    float r = sqrt(fmax(0.0f, 1.0f - fabs(d.z)));
    float a = fmax(x, y), b = fmin(x, y);
    float phi = atan(a > 0.0f ? b / a : 0.0f) * (2.0f / PI_F);
    if (x < y)
        phi = 1.0f - phi;
    float v = phi * r, u = r - v;
    if (d.z < 0.0f) {
        float t = u;
        u = 1.0f - v;
        v = 1.0f - t;
    }
    return (float2)(copysign(u, d.x) + 1.0f, copysign(v, d.y) + 1.0f) * 0.5f;
}

int sample_goniometric_light(const SceneData *sc, const RenderParams *p, const global Light *l, float3 x,
                             float3 n, float2 u, LightSample *ls)
{
#ifdef TEXTURES
    float r2;
    float3 w;
    if (!aim_from_frame(GONIOMETRIC_LIGHT_POSITION(l), GONIOMETRIC_LIGHT_ROTATION(l), x, ls, &r2, &w))
        return 0;
    float3 value = eval_texture(sc, (int)GONIOMETRIC_LIGHT_MAP(l), equal_area_square((float3)(w.x, w.z, w.y)));
    ls->le = GONIOMETRIC_LIGHT_INTENSITY(l) * (value.x / r2);
    return 1;
#else
    return 0;        /* a program without textures has no goniometric light's image */
#endif
}

#ifdef BDPT
/* Light leaving a goniometric light (kernels/bdpt.cl): every direction uniformly (pbrt-v4's
 * GoniometricLight::SampleLe); le is the intensity I(w) along it. */
int emit_goniometric_light(const SceneData *sc, const RenderParams *p, const global Light *l, float4 u,
                           LightEmission *e)
{
#ifdef TEXTURES
    e->p = GONIOMETRIC_LIGHT_POSITION(l);
    e->n = (float3)(0.0f);
    e->d = sample_uniform_sphere(u.x, u.y);
    float3 w = to_light_space(GONIOMETRIC_LIGHT_ROTATION(l), e->d);
    float3 value = eval_texture(sc, (int)GONIOMETRIC_LIGHT_MAP(l), equal_area_square((float3)(w.x, w.z, w.y)));
    e->le = GONIOMETRIC_LIGHT_INTENSITY(l) * value.x;
    e->pdf_pos = 1.0f;
    e->pdf_dir = 1.0f / (4.0f * PI_F);
    e->offset = 0.0f;
    e->prim = -1;
    e->delta = 1;
    return 1;
#else
    return 0;
#endif
}

/* The density per solid angle with which emit_goniometric_light leaves in direction w. */
float pdf_goniometric_emission(const global Light *l, float3 w)
{
    return 1.0f / (4.0f * PI_F);
}
#endif
