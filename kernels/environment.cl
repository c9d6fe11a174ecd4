/* The environment: radiance arriving from infinitely far away, stored as a latitude-longitude map
 * (a constant colour is a 1x1 map). Direction d maps to
 *     u = 1/2 + atan2(d.x, -d.z) / (2 pi) + rotation,   v = acos(d.y) / pi,
 * so the map's centre column lies along -z and its top row is straight up (+y). Lookups are
 * bilinear, wrap around in u, clamp in v, and keep the full HDR range. */

float2 direction_to_latlong(float3 d, float rotation)
{
    float u = 0.5f + atan2(d.x, -d.z) / (2.0f * PI_F) + rotation;
    float v = acos(clamp(d.y, -1.0f, 1.0f)) / PI_F;
    return (float2)(u - floor(u), v);
}

float3 lookup_environment(const global float4 *env, const RenderParams *p, float3 d)
{
    /* a constant colour needs no mapping: skips atan2 and acos for most rays of most scenes */
    if (p->env_width == 1 && p->env_height == 1)
        return env[0].xyz * p->env_scale.xyz;
    float2 uv = direction_to_latlong(d, p->env_rotation);
    float x = uv.x * p->env_width - 0.5f;
    float y = clamp(uv.y * p->env_height - 0.5f, 0.0f, (float)(p->env_height - 1));
    float fx = floor(x), fy = floor(y);
    float ax = x - fx, ay = y - fy;
    int x0 = ((int)fx + p->env_width) % p->env_width;
    int x1 = (x0 + 1) % p->env_width;
    int y0 = (int)fy;
    int y1 = min(y0 + 1, p->env_height - 1);
    float4 top = mix(env[y0 * p->env_width + x0], env[y0 * p->env_width + x1], ax);
    float4 bottom = mix(env[y1 * p->env_width + x0], env[y1 * p->env_width + x1], ax);
    return mix(top, bottom, ay).xyz * p->env_scale.xyz;
}
