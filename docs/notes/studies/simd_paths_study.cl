/* Kernel of docs/notes/studies/simd_paths_study.py: pathtrace's estimator (depth-limited paths with
 * next-event estimation and the power heuristic, kernels/integrator.cl) for scenes of spheres with
 * diffuse or emitting materials under a constant sky, with LANES paths per work-item in OpenCL
 * vectors, as Mitsuba 3's LLVM backend runs its wavefront: every step of every path is computed
 * in all lanes, those whose paths have ended masked off by selects.
 *
 *   spheres      n_spheres float4s: centre, radius
 *   albedo       per sphere: diffuse reflectance (rgb; 0 for an emitter, whose BSDF is black)
 *   emission     per sphere: emitted radiance (rgb)
 *   lights       n_lights sphere indices of the emitters
 *   sky          the constant environment's radiance
 *   env_pick     the probability that a light sample goes to the sky (the rest split evenly
 *                among the emitters)
 *   camera       eye, and the image plane's corner and steps per pixel (x, y) in world space
 *   out          per pixel, the mean radiance of its `spp` samples (rgb as three planes)
 *
 * Work-item k takes pixels k LANES .. k LANES + LANES - 1 of the image in row order. */

#define RAY_EPSILON 1e-4f
#define PI_F 3.14159265358979f

typedef struct {
    floatN x, y, z;
} vec;

vec v_make(floatN x, floatN y, floatN z) { vec v = {x, y, z}; return v; }
vec v_add(vec a, vec b) { return v_make(a.x + b.x, a.y + b.y, a.z + b.z); }
vec v_sub(vec a, vec b) { return v_make(a.x - b.x, a.y - b.y, a.z - b.z); }
vec v_scale(vec a, floatN s) { return v_make(a.x * s, a.y * s, a.z * s); }
vec v_mul(vec a, vec b) { return v_make(a.x * b.x, a.y * b.y, a.z * b.z); }
floatN v_dot(vec a, vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
vec v_unit(vec a) { return v_scale(a, rsqrt(v_dot(a, a))); }
vec v_select(vec a, vec b, intN c) { return v_make(select(a.x, b.x, c), select(a.y, b.y, c), select(a.z, b.z, c)); }
vec v_splat(float3 a) { return v_make((floatN)(a.x), (floatN)(a.y), (floatN)(a.z)); }

uintN hash_lanes(uintN x)
{
    x ^= x >> 16; x *= 0x7feb352dU; x ^= x >> 15; x *= 0x846ca68bU; x ^= x >> 16;
    return x;
}

/* A uniform number in [0, 1) per lane, from (path key, dimension) */
floatN uniform(uintN key, uint dim)
{
    return convert_floatN(hash_lanes(key ^ hash_lanes((uintN)(dim * 0x9e3779b9U + 0x85ebca6bU))) >> 8)
           * (1.0f / 16777216.0f);
}

/* d in the frame of unit normal n (Duff et al. 2017) */
vec to_world(vec v, vec n)
{
    floatN sg = copysign((floatN)(1.0f), n.z), a = -1.0f / (sg + n.z), b = n.x * n.y * a;
    vec s = v_make(1.0f + sg * n.x * n.x * a, sg * b, -sg * n.x);
    vec t = v_make(b, sg + n.y * n.y * a, -n.y);
    return v_add(v_add(v_scale(s, v.x), v_scale(t, v.y)), v_scale(n, v.z));
}

/* A direction about n with density cos / pi */
vec sample_cosine(vec n, floatN u1, floatN u2)
{
    floatN r = sqrt(u1), phi = 2.0f * u2 - 1.0f;
    return to_world(v_make(r * cospi(phi), r * sinpi(phi), sqrt(fmax(1.0f - u1, 0.0f))), n);
}

/* Nearest sphere along o + t d, t in (0, t_max): its index (-1: none), t in *t */
intN nearest_sphere(constant float4 *spheres, int n, vec o, vec d, intN self, floatN *t)
{
    intN hit = -1;
    floatN best = INFINITY;
    for (int s = 0; s < n; ++s) {
        float4 sp = spheres[s];
        vec c = v_sub(o, v_splat(sp.xyz));
        /* the discriminant as r^2 - |c - b d|^2, which keeps its precision where |c| ~ r is
           large (Haines et al., Ray Tracing Gems, ch. 7) */
        floatN b = v_dot(c, d);
        vec f = v_sub(c, v_scale(d, b));
        floatN h = sp.w * sp.w - v_dot(f, f);
        floatN q = sqrt(fmax(h, 0.0f));
        floatN t_s = select(-b - q, -b + q, -b - q <= RAY_EPSILON);
        /* a ray leaves a sphere outwards (the one-sided surfaces are seen from outside), and a
           sphere is convex: it cannot meet the sphere it leaves */
        intN closer = (h >= 0.0f) & (t_s > RAY_EPSILON) & (t_s < best) & ((intN)(s) != self);
        best = select(best, t_s, closer);
        hit = select(hit, (intN)(s), closer);
    }
    *t = best;
    return hit;
}

/* The solid angle density of sampling sphere light `s` uniformly in its cone from x */
floatN pdf_cone(float4 sp, vec x)
{
    vec c = v_sub(v_splat(sp.xyz), x);
    floatN sin2 = sp.w * sp.w / v_dot(c, c);
    floatN cos_max = sqrt(fmax(1.0f - sin2, 0.0f));
    return 1.0f / (2.0f * PI_F * (1.0f - cos_max));
}

kernel void render_lanes(constant float4 *spheres, int n_spheres, constant float4 *albedo,
                         constant float4 *emission, constant int *lights, int n_lights,
                         float4 sky_, float env_pick, float4 eye_, float4 corner_, float4 step_x_,
                         float4 step_y_, int width, int spp, int max_depth, global float *out, int pixels)
{
    int first = get_global_id(0) * LANES;
    intN pixel = (intN)(first) + LANE_INDEX;
    floatN px = convert_floatN(pixel % width), py = convert_floatN(pixel / width);
    vec sky = v_splat(sky_.xyz), eye = v_splat(eye_.xyz);
    float light_pick = (1.0f - env_pick) / max(n_lights, 1);
    vec sum = v_make(0.0f, 0.0f, 0.0f);
    for (int sample = 0; sample < spp; ++sample) {
        uintN key = hash_lanes(as_uintN(pixel) * 0x27d4eb2dU + (uint)sample);
        vec target = v_add(v_add(v_splat(corner_.xyz), v_scale(v_splat(step_x_.xyz), px + uniform(key, 0))),
                           v_scale(v_splat(step_y_.xyz), py + uniform(key, 1)));
        vec o = eye, d = v_unit(v_sub(target, eye));
        vec throughput = v_make(1.0f, 1.0f, 1.0f), radiance = v_make(0.0f, 0.0f, 0.0f);
        vec prev_x = eye, prev_n = v_make(0.0f, 0.0f, 0.0f);
        floatN pdf_prev = 0.0f;                  /* 0: the camera ray (no MIS) */
        intN self = -1, active = (intN)(-1);
        for (int depth = 1; depth <= max_depth && any(active); ++depth) {
            uint dim = 2 + 8 * depth;
            floatN t;
            intN hit = nearest_sphere(spheres, n_spheres, o, d, self, &t);
            /* escaped: the sky, weighted against the light sample that could have found it */
            intN escaped = active & (hit < 0);
            floatN pl_env = env_pick * fmax(v_dot(prev_n, d), 0.0f) / PI_F;
            floatN w_env = select((floatN)(1.0f), pdf_prev * pdf_prev / (pdf_prev * pdf_prev + pl_env * pl_env),
                                  pdf_prev > 0.0f);
            radiance = v_select(radiance, v_add(radiance, v_scale(v_mul(throughput, sky), w_env)), escaped);
            active &= hit >= 0;
            intN k = max(hit, 0);
            vec x = v_add(o, v_scale(d, t));
            vec c = v_make(0.0f, 0.0f, 0.0f), rho = c, le = c;
            floatN radius = 0.0f;
            for (int s = 0; s < n_spheres; ++s) {         /* the hit sphere's data, by selects */
                intN is = k == s;
                c = v_select(c, v_splat(spheres[s].xyz), is);
                radius = select(radius, (floatN)(spheres[s].w), is);
                rho = v_select(rho, v_splat(albedo[s].xyz), is);
                le = v_select(le, v_splat(emission[s].xyz), is);
            }
            vec n = v_scale(v_sub(x, c), 1.0f / radius);
            /* emission met by BSDF sampling, weighted against light sampling from prev_x */
            floatN pl_hit = 0.0f;
            for (int l = 0; l < n_lights; ++l)
                pl_hit = select(pl_hit, light_pick * pdf_cone(spheres[lights[l]], prev_x), k == lights[l]);
            floatN w_hit = select((floatN)(1.0f), pdf_prev * pdf_prev / (pdf_prev * pdf_prev + pl_hit * pl_hit),
                                  pdf_prev > 0.0f);
            intN front = v_dot(n, d) < 0.0f;
            radiance = v_select(radiance, v_add(radiance, v_scale(v_mul(throughput, le), w_hit)), active & front);
            active &= front & (v_dot(rho, rho) > 0.0f);
            if (depth == max_depth)      /* the last vertex: its emission only */
                break;
            if (!any(active))
                break;
            /* next-event estimation: the sky (cosine about n) or an emitter (its cone) */
            floatN u_pick = uniform(key, dim), u1 = uniform(key, dim + 1), u2 = uniform(key, dim + 2);
            intN to_sky = u_pick < env_pick;
            vec wi = sample_cosine(n, u1, u2);
            floatN pdf_l = env_pick * fmax(v_dot(n, wi), 0.0f) / PI_F;
            vec le_l = sky;
            intN target_sphere = -1;
            int chosen_max = n_lights - 1;
            intN chosen = min(convert_intN((u_pick - env_pick) / light_pick), (intN)(chosen_max));
            for (int l = 0; l < n_lights; ++l) {
                intN is = (~to_sky) & (chosen == l);
                float4 sp = spheres[lights[l]];
                vec to_c = v_sub(v_splat(sp.xyz), x);
                floatN dist2 = v_dot(to_c, to_c);
                floatN cos_max = sqrt(fmax(1.0f - sp.w * sp.w / dist2, 0.0f));
                floatN cos_t = 1.0f - u1 * (1.0f - cos_max), sin_t = sqrt(fmax(1.0f - cos_t * cos_t, 0.0f));
                floatN phi = 2.0f * u2 - 1.0f;
                vec axis = v_scale(to_c, rsqrt(dist2));
                vec w_cone = to_world(v_make(sin_t * cospi(phi), sin_t * sinpi(phi), cos_t), axis);
                wi = v_select(wi, w_cone, is);
                pdf_l = select(pdf_l, light_pick / (2.0f * PI_F * (1.0f - cos_max)), is);
                le_l = v_select(le_l, v_splat(emission[lights[l]].xyz), is);
                target_sphere = select(target_sphere, (intN)(lights[l]), is);
            }
            floatN cos_i = v_dot(n, wi);
            floatN pdf_b = fmax(cos_i, 0.0f) / PI_F;
            intN try_light = active & (cos_i > 0.0f) & (pdf_l > 0.0f);
            floatN t_shadow;
            intN blocker = nearest_sphere(spheres, n_spheres, x, wi, k, &t_shadow);
            intN seen = try_light & (blocker == target_sphere);
            floatN w_l = pdf_l * pdf_l / (pdf_l * pdf_l + pdf_b * pdf_b);
            /* f cos / pdf = rho / pi cos / pdf */
            vec contribution = v_scale(v_mul(v_mul(throughput, rho), le_l), cos_i / PI_F * w_l / pdf_l);
            radiance = v_select(radiance, v_add(radiance, contribution), seen);
            /* the bounce: cosine sampling, weight rho */
            vec wo = sample_cosine(n, uniform(key, dim + 3), uniform(key, dim + 4));
            throughput = v_select(throughput, v_mul(throughput, rho), active);
            pdf_prev = select(pdf_prev, fmax(v_dot(n, wo), 0.0f) / PI_F, active);
            prev_x = v_select(prev_x, x, active);
            prev_n = v_select(prev_n, n, active);
            o = v_select(o, x, active);
            d = v_select(d, wo, active);
            self = select(self, k, active);
        }
        sum = v_add(sum, radiance);
    }
    float inv = 1.0f / spp;
    if (first + LANES <= pixels) {
        VSTORE(sum.x * inv, 0, out + first);
        VSTORE(sum.y * inv, 0, out + pixels + first);
        VSTORE(sum.z * inv, 0, out + 2 * pixels + first);
    }
}
