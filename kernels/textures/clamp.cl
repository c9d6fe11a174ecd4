/* clamp: a texture's values clamped into [low, high], after its filtering, as pbrt-v4's
 * materials clamp a reflectance where they evaluate it (app/textures/clamp.py). Its inputs, tex,
 * low and high, are read by the indices generated from their declaration. */

float3 eval_clamp(const SceneData *sc, const global Texture *t, float2 uv, const float3 *r)
{
    return clamp(eval_input(sc, t, CLAMP_INPUT_TEX, uv, r), eval_input(sc, t, CLAMP_INPUT_LOW, uv, r),
                 eval_input(sc, t, CLAMP_INPUT_HIGH, uv, r));
}
