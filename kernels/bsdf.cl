/* The BSDF interface: every material type provides eval, pdf and sample in the local shading
 * frame (z the shading normal, wo and wi pointing away from the surface);
 * eval_bsdf, pdf_bsdf and sample_bsdf dispatch on the material's type tag, and eval_pdf_bsdf
 * gives a light sample both f and pdf from one switch (app/materials/registry.py: EVAL_PDF). Adding a material
 * takes its kernels/bsdfs/ file, its host BSDFType (app/materials: parameters, packing, checks)
 * and its entry in app/materials/registry.py, which gives each type its tag (BSDF_<NAME>) and
 * generates the dispatch (dispatch_source); the scene readers map their formats' names onto it
 * by hand (app/scene/mitsuba.py, app/scene/pbrt/materials.py). The integrator never names a
 * material.
 *
 *   eval_X(m, wo, wi)        f(wo, wi), without the cosine; 0 for delta lobes
 *   pdf_X(m, wo, wi)         the solid-angle density with which sample_X draws wi, its lobe's
 *                            choice included (delta lobes contribute nothing)
 *   sample_X(m, wo, u, &s)   draws wi from three uniforms; returns 0 when no direction results
 *
 * A type whose every lobe is a delta (MATERIAL_DELTA) provides sample_X only: its eval and pdf
 * are 0 for every pair of directions, and the dispatch says so.
 *
 * One-sided materials see wo in the upper hemisphere (the integrator turns two-sided ones' back
 * faces round); transmissive ones (MATERIAL_TRANSMISSIVE) see wo on either side of their
 * front's frame and tell inside from outside by the sign of wo.z. */

/* The material a BSDF reads: the scene's row itself, or, in a program for a scene with textures,
 * the row with its textured parameters looked up at the hit (kernels/shading.cl), a copy in
 * private memory. */
#ifdef TEXTURES
typedef const Material *MaterialRef;
#else
typedef const global Material *MaterialRef;
#endif

/* The row of surface s's material, seen along ray direction d: a blend's chosen component
 * (kernels/bsdfs/blendbsdf.cl) in a program for a scene with blends. */
#ifdef BLEND
#define MATERIAL_ROW(sc, s, d) choose_component(sc, &(sc)->materials[(sc)->prim_material[(s).prim]], &(s), -(d))
#else
#define MATERIAL_ROW(sc, s, d) (&(sc)->materials[(sc)->prim_material[(s).prim]])
#endif

/* Declares `m`, the MaterialRef of surface s's material (a Surface, kernels/bvh.cl), seen along
 * ray direction d, and completes s's shading frame (kernels/frame.cl), a perturbed normal
 * turned for the side d sees (kernels/normal_maps.cl). */
/* PERTURBED_SIDES_AGREE (kernels/normal_maps.cl: perturbed_sides_agree) is 1 without normal maps,
 * written so that a test using it has no constant operand, of which PoCL's compiler warns. */
#ifdef NORMAL_MAPS
#define FACE_PERTURBED_NORMAL(s, wo) face_perturbed_normal(s, wo)
#define PERTURBED_SIDES_AGREE(s, w, wz) perturbed_sides_agree(s, w, wz)
#else
#define FACE_PERTURBED_NORMAL(s, wo)
#define PERTURBED_SIDES_AGREE(s, w, wz) ((void)(wz), 1)
#endif
#ifdef TEXTURES
#define MATERIAL_AT(m, sc, s, d)                                                                  \
    Material m##_shaded = shade_material(sc, MATERIAL_ROW(sc, s, d), &(s));                      \
    MaterialRef m = &m##_shaded;                                                                 \
    FACE_PERTURBED_NORMAL(&(s), -(d));                                                           \
    complete_frame(sc, &(s))
#else
#define MATERIAL_AT(m, sc, s, d)                                                                  \
    MaterialRef m = MATERIAL_ROW(sc, s, d);                                                      \
    complete_frame(sc, &(s))
#endif

/* The radiance surface s emits, seen along ray direction d: all that a path's last vertex needs
 * of its material, which is not shaded there (no texture looked up but an emission texture). */
#ifdef TEXTURES
#define EMISSION_AT(sc, s, d) surface_emission(sc, MATERIAL_ROW(sc, s, d), &(s))
#else
#define EMISSION_AT(sc, s, d) (MATERIAL_ROW(sc, s, d)->emission.xyz)
#endif


/* What a sampled lobe is, as pbrt-v4's BxDFFlags and Mitsuba's BSDFFlags. */
#define LOBE_REFLECTION 1
#define LOBE_TRANSMISSION 2
#define LOBE_DIFFUSE 4
#define LOBE_GLOSSY 8
#define LOBE_DELTA 16

typedef struct {
    float3 wi;
    float3 weight;   /* f cos(theta_i) / pdf; for a delta lobe, its reflectance over its choice
                        probability */
    float pdf;       /* density of wi, the lobe's choice included; for a delta lobe, the choice
                        probability alone (no MIS there) */
    float eta;       /* relative IOR across a refraction (n_t / n_i), else 1: the integrator's
                        Russian roulette undoes the radiance scaling inside dense media with it */
    int lobe;        /* LOBE_* bits */
} BSDFSample;

float3 reflect_local(float3 w)
{
    return (float3)(-w.x, -w.y, w.z);
}
