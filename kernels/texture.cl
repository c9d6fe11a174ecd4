/* The texture interface. A texture is a function of a surface point's texture coordinates uv;
 * every type (kernels/textures/<name>.cl, with its entry in app/textures/registry.py) provides
 *
 *   float3 eval_X(const SceneData *sc, const global Texture *t, float2 uv)
 *
 * its rgb value at the surface's uv. Each texture applies its own uv transform (transform_uv),
 * as each of Mitsuba 3's and pbrt-v4's textures has its own mapping. eval_texture(sc, i, uv)
 * dispatches on the type of row i of the texture table; the registry generates it over the
 * types a scene uses, and the program for a scene without textures has none of this.
 *
 * Types that combine others (checkerboard, scale, mix) read their inputs through eval_input:
 * an input is an image or a constant texture (eval_leaf_texture) or a constant value. Inputs
 * nest one level deep, which the host checks: OpenCL C has no recursion. */

float2 transform_uv(const global Texture *t, float2 uv)
{
    float3 h = (float3)(uv, 1.0f);
    return (float2)(dot(t->to_u.xyz, h), dot(t->to_v.xyz, h));
}
