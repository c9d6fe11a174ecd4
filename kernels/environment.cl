/* The environment: radiance arriving from infinitely far away, stored as a latitude-longitude map
 * (a constant colour is a 1x1 map). A world direction d is first turned into the map's frame,
 * m = F d (F: env_frame, the host's Environment.map_from_world: where the map's zenith lies and
 * its turn about it), then maps to
 *     u = 1/2 + atan2(m.x, -m.z) / (2 pi),   v = acos(m.y) / pi,
 * so the map's centre column lies along its -z and its top row along its +y. Lookups are
 * bilinear, wrap around in u, clamp in v, and keep the full HDR range; the row at v is the
 * host's mapping (texel centres, or Mitsuba 3's first and last rows at the poles). */

float3 to_map_frame(const RenderParams *p, float3 d)
{
    return (float3)(dot(p->env_frame[0].xyz, d), dot(p->env_frame[1].xyz, d), dot(p->env_frame[2].xyz, d));
}

/* (u, v) of a direction m in the map's frame */
float2 direction_to_latlong(float3 m)
{
    float u = 0.5f + atan2(m.x, -m.z) / (2.0f * PI_F);
    float v = acos(clamp(m.y, -1.0f, 1.0f)) / PI_F;
    return (float2)(u - floor(u), v);
}

float3 lookup_environment(const global float4 *env, const RenderParams *p, float3 d)
{
    /* a constant colour needs no mapping: skips atan2 and acos for most rays of most scenes */
    if (p->env_width == 1 && p->env_height == 1)
        return env[0].xyz * p->env_scale.xyz;
    float2 uv = direction_to_latlong(to_map_frame(p, d));
    float x = uv.x * p->env_width - 0.5f;
    float y = clamp(uv.y * p->env_row_scale + p->env_row_offset, 0.0f, (float)(p->env_height - 1));
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

/* The world direction of the map's (u, v): direction_to_latlong's inverse, turned back by F's
 * transpose. */
float3 latlong_to_direction(const RenderParams *p, float u, float v)
{
    float phi = u - 0.5f, theta = 0.5f * v;                 /* in turns */
    float sin_t = SIN_TURNS(theta);
    float3 m = (float3)(sin_t * SIN_TURNS(phi), COS_TURNS(theta), -sin_t * COS_TURNS(phi));
    return p->env_frame[0].xyz * m.x + p->env_frame[1].xyz * m.y + p->env_frame[2].xyz * m.z;
}

/* The interval i of a cdf of n intervals (cdf[0] = 0, cdf[n] = 1) with cdf[i] <= x < cdf[i+1];
 * intervals of zero width are never returned. */
int find_interval(const global float *cdf, int n, float x)
{
    int lo = 0, hi = n;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (cdf[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* Importance sampling of the map: a piecewise-constant 2D distribution over its texels,
 * proportional to luminance times sin(theta) (pbrt-v4, section 12.5.2), sampled row first
 * (marginal: height + 1 values) then column (conditional: height rows of width + 1 values).
 * The density per solid angle is pdf(u, v) / (2 pi^2 sin(theta)). */
float pdf_environment_map(const global float *marginal, const global float *conditional,
                          const RenderParams *p, float3 d)
{
    float3 m = to_map_frame(p, d);
    float sin_t = sqrt(max(0.0f, 1.0f - m.y * m.y));
    if (sin_t <= 0.0f)
        return 0.0f;
    float2 uv = direction_to_latlong(m);
    int w = p->env_width, h = p->env_height;
    int row = min((int)(uv.y * h), h - 1), col = min((int)(uv.x * w), w - 1);
    const global float *c = conditional + row * (w + 1);
    float pdf_uv = (marginal[row + 1] - marginal[row]) * h * (c[col + 1] - c[col]) * w;
    return pdf_uv / (2.0f * PI_F * PI_F * sin_t);
}

float3 sample_environment_map(const global float *marginal, const global float *conditional,
                              const RenderParams *p, float u1, float u2)
{
    int w = p->env_width, h = p->env_height;
    int row = find_interval(marginal, h, u1);
    float v = (row + (u1 - marginal[row]) / (marginal[row + 1] - marginal[row])) / h;
    const global float *c = conditional + row * (w + 1);
    int col = find_interval(c, w, u2);
    float u = (col + (u2 - c[col]) / (c[col + 1] - c[col])) / w;
    return latlong_to_direction(p, u, v);
}
