/* Colours: linear sRGB triples, as the scene's parameters and the accumulation hold them. */

/* The luminance of a linear sRGB colour (Rec. 709 weights, as Mitsuba 3's `luminance`): the
 * value of a colour texture where a material's parameter is a number (Mitsuba's eval_1), and
 * the brightness by which the principled BSDF normalises its tints. */
float luminance(float3 c)
{
    return dot(c, (float3)(0.212671f, 0.715160f, 0.072169f));
}
