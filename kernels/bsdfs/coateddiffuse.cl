/* coateddiffuse: pbrt-v4's `coateddiffuse`, a Lambertian base under a dielectric coating
 * (smooth, or rough with GGX microfacets), with a layer of homogeneous medium between them,
 * evaluated and sampled by random walks between the two (kernels/layered.cl).
 *
 * Parameters (Material):
 *   p0.xyz  reflectance of the base                        p0.w  the coating's alpha (0: smooth)
 *   p1.x    eta, the coating's IOR                         p1.y  thickness of the layer
 *   p1.z    g of the layer's phase function                p1.w  maxdepth, events per walk
 *   p2.xyz  albedo of the layer's medium (0: it absorbs)   p2.w  nsamples, walks per estimate */

Layers coated_diffuse(MaterialRef m)
{
    Layers l;
    l.top.eta = m->p1.x;
    l.top.alpha = (float2)(m->p0.w);
    l.top.beckmann = 0;
    l.metal = 0;
    l.base = m;
    l.rho = m->p0.xyz;
    l.albedo = m->p2.xyz;
    l.thickness = m->p1.y;
    l.g = m->p1.z;
    l.max_depth = (int)m->p1.w;
    l.samples = (int)m->p2.w;
    return l;
}

LAYERED_BSDF(coateddiffuse, coated_diffuse)
