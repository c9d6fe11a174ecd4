/* The image on its way to a window over a discrete GPU's bus (app/viewer/display.py): the mean
 * radiance of each pixel as half floats, 8 bytes a pixel for the host to copy instead of the 16
 * of the float sums, with a count of 1 in w. The window's shader (shaders/display.frag) then
 * applies exposure, the tone curve and sRGB, so that changing them needs no new copy.
 * (Tonemapping to 8 bits here would halve the copy again, but the sRGB curve's pow costs PoCL
 * 50 ms a frame at 1280x720 on two cores; this kernel takes 0.5 ms.) */

/* One work-item per pixel. sum: radiance sums in rgb and the pixel's sample count in w (while a
 * pass is under way its rows hold one sample more than the others); a pixel with no sample yet
 * is black. Radiance beyond the largest half float (a sun) is clamped to it (65504), not made
 * infinite, which the ACES curve would turn into NaN (inf / inf). */
kernel void mean_half4(global const float4 *sum, int pixels, global half *out)
{
    int k = get_global_id(0);
    if (k >= pixels)
        return;
    float4 s = sum[k];
    float3 mean = s.w > 0.0f ? fmin(s.xyz / s.w, 65504.0f) : (float3)(0.0f);
    vstore_half4((float4)(mean, 1.0f), k, out);
}
