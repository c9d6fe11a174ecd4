#version 330 core
// The image as the user sees it: mean = rgb / a, exposure, tone curve, sRGB. The same steps as
// app/io/tonecurve.py, which writes the PNG screenshots.
uniform sampler2D radiance;       // rgb: radiance summed over a samples (app/viewer/display.py: the
                                  // accumulation buffer; or a mean, or the denoised image, a = 1)
uniform float exposure;           // stops
uniform int curve;                // 0: standard (clip), 1: ACES fit (Narkowicz 2015)
in vec2 uv;
out vec4 color;

vec3 aces_fit(vec3 x)
{
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 linear_to_srgb(vec3 x)
{
    x = clamp(x, 0.0, 1.0);
    return mix(12.92 * x, 1.055 * pow(x, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), x));
}

void main()
{
    vec4 t = texture(radiance, uv);
    vec3 x = (t.a > 0.0 ? t.rgb / t.a : vec3(0.0)) * exp2(exposure);
    if (curve == 1)
        x = aces_fit(x);
    color = vec4(linear_to_srgb(x), 1.0);
}
