/* Normal maps and bump maps (Mitsuba 3's `normalmap` and `bumpmap`; pbrt-v4's `normalmap` and
 * `displacement`): the shading normal perturbed at each hit, before the BSDF sees it. Compiled
 * in only for scenes that have one (NORMAL_MAPS).
 *
 * A normal map's rgb in [0, 1] holds a unit vector of Mitsuba's shading frame, 2 rgb - 1. A bump
 * map is a height field h(u, v) over the surface: dp/du and dp/dv are tilted by its slopes along
 * the normal, p' = p + h n (Blinn 1978, with Mitsuba's first-order terms), and the normal is
 * their cross product. The integrator weighs what a perturbed surface reflects by
 * shadow_terminator, as Mitsuba 3.9's normal and bump maps both do (their common PerturbedBSDF,
 * eval_shadow_terminator, since commit e32d7180 "Improve bump and normal mapping"); pbrt-v4's,
 * which a pbrt file's materials take, do not (perturb_normal). */

#define SLOT_NORMAL_MAP 20   /* app/materials/table.py */
#define SLOT_BUMP_MAP 24

/* The slopes (dh/du, dh/dv) of bump map texture i: a bitmap's, or a scaled bitmap's (Mitsuba's
 * `scale`) times its factor; the host allows no other. */
float2 bump_slopes(const SceneData *sc, int i, float2 uv)
{
    const global Texture *t = &sc->textures[i];
    float k = 1.0f;
    if (t->type == TEXTURE_SCALE) {
        k = t->value[1].x;
        t = &sc->textures[t->input[0]];
    }
    return k * grad_bitmap(sc, t, uv);
}

/* Mitsuba 3's shadowing term for perturbed normals (Conty Estevez et al., "A Microfacet-Based
 * Shadowing Function to Solve the Bump Terminator Problem", Ray Tracing Gems, 2019): the
 * perturbation's tilt is read as the roughness of microfacets, alpha^2 = min(tan^2(tilt) / 8, 1),
 * whose Smith shadowing of direction w, 2 / (1 + sqrt(1 + alpha^2 tan^2(theta_w))) with theta_w
 * from the unperturbed normal, darkens the light that grazes the surface (the hard terminator of
 * strong normal maps). 1 where nothing was perturbed. */
float shadow_terminator(const Surface *s, float3 w)
{
    if (s->terminator <= 0.0f)
        return 1.0f;
    float c = dot(w, s->ns_unperturbed);
    float tan2 = fmax(0.0f, 1.0f - c * c) / fmax(c * c, 1e-12f);
    return 2.0f / (1.0f + sqrt(1.0f + s->terminator * tan2));
}

/* s's shading normal perturbed by material `row`'s normal or bump map, if it has one: the
 * perturbed normal m in the frame (t_s, t_t, ns), t_s = dp/du made orthogonal to ns and
 * t_t = ns x t_s (the front's, on a two-sided back whose ns is turned round), is a normal map's
 * 2 rgb - 1, or a bump map's normal of the tilted derivatives, on the geometric normal's side. As
 * Mitsuba 3.9's `normalmap` and `bumpmap` (one base class, PerturbedBSDF), m's tilt sets the
 * shadowing term, and m is left for face_perturbed_normal to turn by the side it is seen from. As
 * pbrt-v4's (MATERIAL_PBRT_PERTURBATION; materials.h: NormalMap, BumpMap), m is turned whole to
 * the geometric normal's side (interaction.h: SetShadingGeometry, FaceForward), with no
 * shadowing term. */
void perturb_normal(const SceneData *sc, const global Material *row, float2 uv, Surface *s)
{
    for (int i = row->textures;; ++i) {
        TextureBinding b = sc->bindings[i];
        if (b.slot == SLOT_NORMAL_MAP || b.slot == SLOT_BUMP_MAP) {
            float3 n = s->ns;
            float3 t_s = shading_tangent(sc, s), t_t = s->side * cross(n, t_s);
            float3 m;
            if (b.slot == SLOT_NORMAL_MAP) {
                m = 2.0f * eval_texture(sc, b.texture, uv) - 1.0f;
            } else {
                float3 dpdu, dpdv;
                surface_derivatives(sc, s, &dpdu, &dpdv);
                float2 slope = bump_slopes(sc, b.texture, uv);
                float3 du = dpdu + n * (slope.x - dot(n, dpdu));
                float3 dv = dpdv + n * (slope.y - dot(n, dpdv));
                float3 bumped = cross(du, dv);
                if (dot(bumped, s->ng) < 0.0f)
                    bumped = -bumped;
                m = (float3)(dot(bumped, t_s), dot(bumped, t_t), dot(bumped, n));
            }
            float len_m = length(m);
            if (!(len_m > 0.0f) || !isfinite(len_m))
                return;
            m /= len_m;
            float3 ns = m.x * t_s + m.y * t_t + m.z * n;
            if (row->flags & MATERIAL_PBRT_PERTURBATION) {
                s->ns = dot(ns, s->ng) < 0.0f ? -ns : ns;
                return;
            }
            s->terminator = fmin(0.125f * fmax(0.0f, 1.0f - m.z * m.z) / fmax(m.z * m.z, 1e-12f), 1.0f);
            s->ns = ns;
            return;
        }
        if (b.last)
            return;
    }
}

/* Whether Mitsuba's normal maps turn s's perturbed normal m for wo, the direction towards the
 * camera's side: where m faces away from wo, m's tangential part is turned round (Schuessler et
 * al., "Microfacet-based Normal Mapping for Robust Monte Carlo Path Tracing", 2017, the flip
 * Mitsuba 3's PerturbedBSDF makes). Never for pbrt's maps or an unperturbed normal, whose
 * terminator is 0. */
int turns_perturbed_normal(const Surface *s, float3 wo)
{
    return s->terminator > 0.0f && dot(wo, s->ns_unperturbed) * dot(wo, s->ns) <= 0.0f;
}

/* Whether Mitsuba's normal maps carry light along world direction w, whose cosine in s's
 * perturbed frame is wz: the perturbed and the unperturbed shading normals put w on one side
 * (Mitsuba 3's PerturbedBSDF tests it in eval, pdf and sample, src/bsdfs/normalmap.cpp); always
 * for pbrt's maps (pbrt-v4 tests no side) and an unperturbed normal, whose terminator is 0. */
int perturbed_sides_agree(const Surface *s, float3 w, float wz)
{
    return s->terminator <= 0.0f || dot(w, s->ns_unperturbed) * wz > 0.0f;
}

/* Turns s's perturbed normal m round about the unperturbed n: m.xy negated, 2 m.z n - m. */
void turn_perturbed_normal(Surface *s)
{
    s->ns = 2.0f * dot(s->ns, s->ns_unperturbed) * s->ns_unperturbed - s->ns;
}

/* s's perturbed normal as wo, the camera's side, sees it (turns_perturbed_normal). */
void face_perturbed_normal(Surface *s, float3 wo)
{
    if (turns_perturbed_normal(s, wo))
        turn_perturbed_normal(s);
}
