/* clamp: a texture's values clamped into [low, high], after its filtering, as pbrt-v4's
 * materials clamp a reflectance where they evaluate it (app/textures/clamp.py). Its input, tex,
 * is read by the index generated from its declaration; low and high, constants, lie in the
 * slots no input takes, value[1] and value[2] (Clamp.pack). */

float3 eval_clamp(const SceneData *sc, const global Texture *t, float2 uv, const float3 *r)
{
    return clamp(eval_input(sc, t, CLAMP_INPUT_TEX, uv, r), t->value[1].xyz, t->value[2].xyz);
}
