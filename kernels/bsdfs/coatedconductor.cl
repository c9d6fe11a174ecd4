/* coatedconductor: pbrt-v4's `coatedconductor`, a metal base (smooth, or rough with GGX
 * microfacets: kernels/metal.cl) under a dielectric coating (smooth or rough), with a layer of
 * homogeneous medium between them, evaluated and sampled by random walks between the two
 * (kernels/layered.cl). A smooth coating over a mirror with a clear layer is a delta BSDF
 * (MATERIAL_DELTA, app/materials/layered.py).
 *
 * Parameters (Material):
 *   p0.xyz  the conductor's eta                            p0.w  the coating's alpha (0: smooth)
 *   p1.xyz  the conductor's k                              p1.w  the conductor's alpha (0: smooth)
 *   p2.xyz  albedo of the layer's medium (0: it absorbs)   p2.w  thickness of the layer
 *   table[0]  the coating's IOR     table[1]  g of the layer's phase function
 *   table[2]  maxdepth              table[3]  nsamples
 *   table[4]  the coating's alpha along the bitangent     table[5]  the conductor's */

Layers coated_conductor(MaterialRef m)
{
    Layers l;
    l.top.eta = m->table[0];
    l.top.alpha = (float2)(m->p0.w, m->table[4]);
    l.top.beckmann = 0;
    l.metal = 1;
    l.base.eta = m->p0.xyz;
    l.base.k = m->p1.xyz;
    l.base.alpha = (float2)(m->p1.w, m->table[5]);
    l.base.beckmann = 0;
    l.rho = (float3)(0.0f);
    l.albedo = m->p2.xyz;
    l.thickness = m->p2.w;
    l.g = m->table[1];
    l.max_depth = (int)m->table[2];
    l.samples = (int)m->table[3];
    return l;
}

LAYERED_BSDF(coatedconductor, coated_conductor)
