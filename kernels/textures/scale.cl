/* scale: a texture times a factor (pbrt-v4's `scale`; Mitsuba's <texture> inside a `scale`).
 *
 * Fields (Texture):
 *   input 0   the texture (pbrt's tex)
 *   input 1   the factor (pbrt's scale), a constant or a texture
 */

float3 eval_scale(const SceneData *sc, const global Texture *t, float2 uv, const float3 *r)
{
    return eval_input(sc, t, 0, uv, r) * eval_input(sc, t, 1, uv, r);
}
