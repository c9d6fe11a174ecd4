/* checkerboard: two colours in alternating squares of the unit of uv (Mitsuba 3's
 * `checkerboard`): input 0 where the fractional parts of u and v lie in the same half of
 * [0, 1), input 1 elsewhere.
 *
 * Its inputs, color0 and color1 (constants or textures, kernels/texture.cl), are read by the
 * indices generated from their declaration (app/textures/checkerboard.py); to_u and to_v are the
 * uv transform (Mitsuba's to_uv): a scale of 4 makes 4 x 4 squares. */

float3 eval_checkerboard(const SceneData *sc, const global Texture *t, float2 uv, const float3 *r)
{
    float2 st = transform_uv(t, uv);
    int upper_u = st.x - floor(st.x) > 0.5f, upper_v = st.y - floor(st.y) > 0.5f;
    return eval_input(sc, t, upper_u == upper_v ? CHECKERBOARD_INPUT_COLOR0 : CHECKERBOARD_INPUT_COLOR1, uv, r);
}
