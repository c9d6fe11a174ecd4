/* Where a path tracer's time goes, tracing against the rest (`pathtrace bench --trace-split`,
 * app/bench/trace_split.py). The megakernel (kernels/integrator.cl) keeps a path's whole state live
 * while each ray walks the BVH, which on a GPU costs registers, hence threads in flight, hence
 * hidden memory latency. A wavefront path tracer (Laine, Karras and Aila, "Megakernels
 * Considered Harmful", HPG 2013) traces rays in a kernel that holds nothing else. These kernels
 * bound what that split could gain: record_rays writes the rays of depth-2 paths as the
 * megakernel traces them (the camera ray, and at its hit one light sample's shadow ray and one
 * BSDF sample's bounce, with the first vertex's rules), and trace_rays traces them again with
 * nothing but the walk. Built only for the bench, appended to a scene's program.
 *
 *   rays    per pixel three rays, camera, bounce and shadow, each two float4: the origin and
 *           t_max, then the unit direction and, as int bits, the primitive the ray leaves (-1:
 *           none). A zero direction is no ray (the camera ray escaped, the surface was a back
 *           face, the sample was refused). Scenes with media or a two-level BVH are not split
 *           (app/bench/trace_split.py refuses them).
 *   which   0, 1 or 2: trace_rays traces each pixel's camera, bounce or shadow ray.
 *   hits    per pixel, the primitive hit (-1: none), 1 or 0 for an occluded shadow ray or not,
 *           and -2 where there was no ray. */

void write_ray(global float4 *rays, int k, float3 o, float t_max, float3 d, int self)
{
    rays[k] = (float4)(o, t_max);
    rays[k + 1] = (float4)(d, as_float(self));
}

/* The shadow ray of light sample ls from o, as kernels/integrator.cl's light_visibility traces
 * it: its unit direction into *d, and its t_max, just short of the point on the light (INFINITY
 * for a light at infinity). */
float shadow_ray(float3 o, const LightSample *ls, float3 *d)
{
    *d = ls->wi;
    if (ls->flags & LIGHT_AT_INFINITY)
        return INFINITY;
    float t = norm(ls->y - o);
    *d = (ls->y - o) / t;
    return t * (1.0f - SHADOW_EPSILON);
}

kernel void record_rays(SCENE_KERNEL_ARGS, const RenderParams p, global float4 *rays)
{
    SceneData sc = SCENE_DATA(p.num_spheres, p.layout);
    int x = get_global_id(0), y = get_global_id(1);
    if (x >= p.width || y >= p.height)
        return;
    int k = (y * p.width + x) * 6;
    write_ray(rays, k + 2, (float3)(0.0f), 0.0f, (float3)(0.0f), -1);
    write_ray(rays, k + 4, (float3)(0.0f), 0.0f, (float3)(0.0f), -1);
    Rng rng = make_rng(x, y, p.sample_start, p.seed);
    CameraRay ray = sample_camera_ray(&p, x, y, &rng);
    write_ray(rays, k, ray.o, INFINITY, ray.d, -1);
    Hit hit = intersect_scene(&sc, ray.o, ray.d, INFINITY, NO_PRIM);
    if (hit.prim < 0)
        return;
    Surface s = surface_at(&sc, &hit, ray.o, ray.d);
    int flags = sc.materials[sc.prim_material[hit.prim]].flags;
    if (dot(s.ng, ray.d) >= 0.0f) {
        if (flags & MATERIAL_TWOSIDED)
            turn_round(&s);
        else if (!(flags & MATERIAL_TRANSMISSIVE))
            return;
    }
    MATERIAL_AT(m, &sc, s, ray.d);
    float3 wo = to_shading(&s, -ray.d);
    if (!(m->flags & MATERIAL_DELTA) && p.num_lights > 0) {
        LightSample ls = sample_light(&sc, &p, s.p, s.ns, next_bits4(&rng), &rng);
        float3 wi = to_shading(&s, ls.wi);
        if (ls.pdf > 0.0f && PERTURBED_SIDES_AGREE(&s, ls.wi, wi.z) && any(eval_bsdf(m, wo, wi) != 0.0f)) {
            float3 o = offset_ray_origin(s.p, s.offset, s.ng, ls.wi), d;
            float t_max = shadow_ray(o, &ls, &d);
            write_ray(rays, k + 4, o, t_max, d, hit.prim);
        }
    }
    BSDFSample bs;
    bs.eta = 1.0f;
    if (sample_bsdf(m, wo, next_uniform4(&rng).xyz, &bs)) {
        float3 wi = from_shading(&s, bs.wi);
        if (PERTURBED_SIDES_AGREE(&s, wi, bs.wi.z))
            write_ray(rays, k + 2, offset_ray_origin(s.p, s.offset, s.ng, wi), INFINITY, wi, hit.prim);
    }
}

/* Launched over the image as the megakernel is (8x8 work-groups of pixels), so that a warp's
 * rays are as coherent as the megakernel's. */
kernel void trace_rays(SCENE_KERNEL_ARGS, const RenderParams p, const global float4 *rays, int which,
                       global int *hits)
{
    SceneData sc = SCENE_DATA(p.num_spheres, p.layout);
    int x = get_global_id(0), y = get_global_id(1);
    if (x >= p.width || y >= p.height)
        return;
    int i = y * p.width + x, k = i * 6 + 2 * which;
    float4 o = rays[k], d = rays[k + 1];
    if (all(d.xyz == 0.0f))
        hits[i] = -2;
    else if (which == 2)
        hits[i] = occluded(&sc, o.xyz, d.xyz, o.w, as_int(d.w));
    else
        hits[i] = intersect_scene(&sc, o.xyz, d.xyz, o.w, as_int(d.w)).prim;
}
