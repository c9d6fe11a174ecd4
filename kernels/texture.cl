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
 * an input is a texture that combines none (eval_leaf_texture), a constant value, or the value
 * of a texture that combines others, in a register. Textures nest to any depth (pbrt-v4's do),
 * and OpenCL C has no recursion: the host (app/textures/table.py) lays out the combining
 * textures of each tree that a material reads as a program, rows in post-order ending with the
 * tree's root, each pushing its value on a stack of registers after popping its combining
 * inputs' (Sethi and Ullman's order, the input needing more registers first, which keeps a
 * chain of any length within one register and a tree within log2 of its size).
 * eval_texture runs it. */

float2 transform_uv(const global Texture *t, float2 uv)
{
    float3 h = (float3)(uv, 1.0f);
    return (float2)(dot(t->to_u.xyz, h), dot(t->to_v.xyz, h));
}
