/* constant: one colour everywhere (a scene file's plain value where a texture may stand).
 *
 * Fields (Texture):
 *   value[0].xyz   the colour
 */

float3 eval_constant(const SceneData *sc, const global Texture *t, float2 uv)
{
    return t->value[0].xyz;
}
