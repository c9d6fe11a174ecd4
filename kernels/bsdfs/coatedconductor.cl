/* coatedconductor: pbrt-v4's `coatedconductor`, a metal base (smooth, or rough with GGX
 * microfacets) under a dielectric coating (smooth or rough), with a layer of homogeneous medium
 * between them, evaluated and sampled by random walks between the two (kernels/layered.cl). Its
 * base is read as a roughconductor (a mirror where conductor_alpha is 0), in the slots its host
 * shares with roughconductor (CoatedConductor.reads_as, app/materials/layered.py); the rest
 * through COATEDCONDUCTOR_<PARAM>, generated from their slots there. A smooth coating over a
 * mirror with a clear layer is a delta BSDF (MATERIAL_DELTA). */

Layers coated_conductor(MaterialRef m)
{
    Layers l;
    l.top.eta = COATEDCONDUCTOR_INTERFACE_ETA(m);
    l.top.alpha = (float2)(COATEDCONDUCTOR_ALPHA(m), COATEDCONDUCTOR_ALPHA_V(m));
    l.top.beckmann = 0;
    l.metal = 1;
    l.base = m;
    l.rho = (float3)(0.0f);
    l.albedo = COATEDCONDUCTOR_ALBEDO(m);
    l.thickness = COATEDCONDUCTOR_THICKNESS(m);
    l.g = COATEDCONDUCTOR_G(m);
    l.max_depth = (int)COATEDCONDUCTOR_MAXDEPTH(m);
    l.samples = (int)COATEDCONDUCTOR_NSAMPLES(m);
    return l;
}

LAYERED_BSDF(coatedconductor, coated_conductor)
