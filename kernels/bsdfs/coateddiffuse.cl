/* coateddiffuse: pbrt-v4's `coateddiffuse`, a Lambertian base under a dielectric coating
 * (smooth, or rough with GGX microfacets), with a layer of homogeneous medium between them,
 * evaluated and sampled by random walks between the two (kernels/layered.cl). Its parameters
 * are read through COATEDDIFFUSE_<PARAM>, generated from their slots on the host
 * (app/materials/layered.py). */

Layers coated_diffuse(MaterialRef m)
{
    Layers l;
    l.top.eta = COATEDDIFFUSE_ETA(m);
    l.top.alpha = (float2)(COATEDDIFFUSE_ALPHA(m));
    l.top.beckmann = 0;
    l.metal = 0;
    l.base = m;
    l.rho = COATEDDIFFUSE_REFLECTANCE(m);
    l.albedo = COATEDDIFFUSE_ALBEDO(m);
    l.thickness = COATEDDIFFUSE_THICKNESS(m);
    l.g = COATEDDIFFUSE_G(m);
    l.max_depth = (int)COATEDDIFFUSE_MAXDEPTH(m);
    l.samples = (int)COATEDDIFFUSE_NSAMPLES(m);
    return l;
}

LAYERED_BSDF(coateddiffuse, coated_diffuse)
