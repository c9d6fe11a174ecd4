/* The BSDF interface: every material type provides eval, pdf and sample in the local shading
 * frame (z the shading normal, wo and wi pointing away from the surface);
 * eval_bsdf, pdf_bsdf and sample_bsdf dispatch on the material's type tag. Adding a material
 * means one kernels/bsdfs/ file and one entry in app/materials.py, whose registry gives each
 * type its tag (BSDF_<NAME>) and generates the dispatch (app/materials.py, dispatch_source);
 * the integrator never names a material.
 *
 *   eval_X(m, wo, wi)        f(wo, wi), without the cosine
 *   pdf_X(m, wo, wi)         the solid-angle density with which sample_X draws wi (0 for a
 *                            delta lobe)
 *   sample_X(m, wo, u, &s)   draws wi from three uniforms; returns 0 when no direction results
 */

#define MATERIAL_TWOSIDED 1   /* the same BSDF on both sides (front-side frame mirrored) */
#define MATERIAL_DELTA 2      /* every lobe is a delta: no light sampling here */

/* What a sampled lobe is, as pbrt-v4's BxDFFlags and Mitsuba's BSDFFlags. */
#define LOBE_REFLECTION 1
#define LOBE_TRANSMISSION 2
#define LOBE_DIFFUSE 4
#define LOBE_GLOSSY 8
#define LOBE_DELTA 16

typedef struct {
    float3 wi;
    float3 weight;   /* f cos(theta_i) / pdf; for a delta lobe, the reflectance itself */
    float pdf;       /* density of wi; for a delta lobe, that of choosing it (no MIS there) */
    int lobe;        /* LOBE_* bits */
} BSDFSample;

/* A shading frame: t, b, n orthonormal. */
typedef struct {
    float3 t, b, n;
} Frame;

Frame make_shading_frame(float3 n)
{
    Frame f;
    make_frame(n, &f.t, &f.b);
    f.n = n;
    return f;
}

float3 to_shading(const Frame *f, float3 v)
{
    return (float3)(dot(v, f->t), dot(v, f->b), dot(v, f->n));
}

float3 from_shading(const Frame *f, float3 v)
{
    return v.x * f->t + v.y * f->b + v.z * f->n;
}
