/* scale: a texture times a factor (pbrt-v4's `scale`; Mitsuba's <texture> inside a `scale`).
 * Its inputs, tex and scale (a constant or a texture), are read by the indices generated from
 * their declaration (app/textures/scale.py). */

float3 eval_scale(const SceneData *sc, const global Texture *t, float2 uv, const float3 *r)
{
    return eval_input(sc, t, SCALE_INPUT_TEX, uv, r) * eval_input(sc, t, SCALE_INPUT_SCALE, uv, r);
}
