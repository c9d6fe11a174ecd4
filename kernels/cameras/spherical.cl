/* A spherical camera (app/cameras/spherical.py; pbrt-v4's `spherical`, src/pbrt/cameras.cpp,
 * SphericalCamera::GenerateRay): every direction around the eye, the film's (u, v) = (sx / width,
 * sy / height) mapped onto the sphere whatever the image's aspect.
 *
 *   p->eye       the centre
 *   p->forward   the camera's unit axes: pbrt's camera space +z, +x and +y
 *   p->right
 *   p->up
 *   p->lens.x    the mapping: 0 equal-area (pbrt-v4's default), 1 equirectangular
 *
 * Both mappings give a direction with +z up (pbrt swaps its y and z into camera space).
 * Equirectangular: theta = pi v from up, phi = 2 pi u from right towards forward. Equal-area:
 * Clarberg's octahedral square (pbrt-v4's EqualAreaSquareToSphere, the layout of its environment
 * maps), the film point first mirrored back into the square where a filter's offset took it
 * past an edge (WrapEqualAreaSquare). */

float3 spherical_equal_area(float2 uv)
{
    if (uv.x < 0.0f) {
        uv = (float2)(-uv.x, 1.0f - uv.y);
    } else if (uv.x > 1.0f) {
        uv = (float2)(2.0f - uv.x, 1.0f - uv.y);
    }
    if (uv.y < 0.0f) {
        uv = (float2)(1.0f - uv.x, -uv.y);
    } else if (uv.y > 1.0f) {
        uv = (float2)(1.0f - uv.x, 2.0f - uv.y);
    }
    float u = 2.0f * uv.x - 1.0f, v = 2.0f * uv.y - 1.0f;
    float signed_distance = 1.0f - (fabs(u) + fabs(v));
    float r = 1.0f - fabs(signed_distance);
    float phi = (r == 0.0f ? 1.0f : (fabs(v) - fabs(u)) / r + 1.0f) * (PI_F / 4.0f);
    float s = r * sqrt(fmax(0.0f, 2.0f - r * r));
    return (float3)(copysign(cos(phi), u) * s, copysign(sin(phi), v) * s, copysign(1.0f - r * r, signed_distance));
}

CameraRay generate_spherical_ray(const RenderParams *p, float sx, float sy, float2 u)
{
    float2 uv = (float2)(sx / p->width, sy / p->height);
    float3 d;
    if (p->lens.x == 0.0f) {
        d = spherical_equal_area(uv);
    } else {
        float theta = PI_F * uv.y, phi = 2.0f * PI_F * uv.x;
        d = (float3)(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
    }
    CameraRay ray = {p->eye.xyz, unit(d.x * p->right.xyz + d.y * p->forward.xyz + d.z * p->up.xyz)};
    return ray;
}
