/* coatedconductor: pbrt-v4's `coatedconductor`, a metal base (smooth, or rough with GGX
 * microfacets) under a dielectric coating (smooth or rough), with a layer of homogeneous medium
 * between them, evaluated and sampled by random walks between the two (kernels/layered.cl). Its
 * p0..p2 are a roughconductor's, which is the base (a mirror where alpha is 0). A smooth
 * coating over a mirror with a clear layer is a delta BSDF (MATERIAL_DELTA,
 * app/materials/layered.py).
 *
 * Parameters (Material):
 *   p0.xyz  the conductor's eta                  p0.w  the conductor's alpha (0: a mirror)
 *   p1.xyz  the conductor's k                    p1.w  its alpha along the bitangent
 *   p2      (1, 1, 1, 0): roughconductor's specular_reflectance and distribution (GGX)
 *   table[0]  the coating's IOR     table[1]  g of the layer's phase function
 *   table[2]  maxdepth              table[3]  nsamples
 *   table[4]  the coating's alpha (0: smooth)    table[5]  along the bitangent
 *   table[6]  thickness of the layer             table[7..9]  albedo of its medium */

Layers coated_conductor(MaterialRef m)
{
    Layers l;
    l.top.eta = m->table[0];
    l.top.alpha = (float2)(m->table[4], m->table[5]);
    l.top.beckmann = 0;
    l.metal = 1;
    l.base = m;
    l.rho = (float3)(0.0f);
    l.albedo = (float3)(m->table[7], m->table[8], m->table[9]);
    l.thickness = m->table[6];
    l.g = m->table[1];
    l.max_depth = (int)m->table[2];
    l.samples = (int)m->table[3];
    return l;
}

LAYERED_BSDF(coatedconductor, coated_conductor)
