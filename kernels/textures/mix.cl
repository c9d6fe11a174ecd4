/* mix: a blend of two textures, (1 - amount) tex1 + amount tex2 (pbrt-v4's `mix`).
 * Its inputs, tex1, tex2 and amount, are read by the indices generated from their declaration
 * (app/textures/mix.py); of amount, a number texture, the first channel is used, as pbrt's float
 * image textures read an image's first channel. */

float3 eval_mix(const SceneData *sc, const global Texture *t, float2 uv, const float3 *r)
{
    float amount = eval_input(sc, t, MIX_INPUT_AMOUNT, uv, r).x;
    float3 tex1 = eval_input(sc, t, MIX_INPUT_TEX1, uv, r);
    /* OpenCL's mix() leaves an amount beyond [0, 1] undefined; pbrt-v4 extrapolates there */
    return tex1 + (eval_input(sc, t, MIX_INPUT_TEX2, uv, r) - tex1) * amount;
}
