/* mix: a blend of two textures, (1 - amount) tex1 + amount tex2 (pbrt-v4's `mix`).
 *
 * Fields (Texture):
 *   input 0, input 1   tex1 and tex2
 *   input 2            amount, a number texture: its first channel is used, as pbrt's float
 *                      image textures read an image's first channel
 */

float3 eval_mix(const SceneData *sc, const global Texture *t, float2 uv, const float3 *r)
{
    float amount = eval_input(sc, t, 2, uv, r).x;
    return mix(eval_input(sc, t, 0, uv, r), eval_input(sc, t, 1, uv, r), amount);
}
