/* Participating media in the path tracer (a MEDIA program's; Mitsuba 3's `volpath`, pbrt-v4's
 * VolPathIntegrator): which medium a ray is in, what of a light's radiance crosses the media and
 * null boundaries on the way to a point, and next-event estimation at a scattering inside a
 * medium. kernels/integrator.cl samples the free flights (kernels/media/) and the phase
 * function (kernels/phase.cl) with them.
 *
 * A primitive either bounds media, with a medium on each side (or vacuum), or changes nothing:
 * a ray keeps its medium across it (prim_media, kernels/types.h), as pbrt-v4's shapes whose
 * MediumInterface is no transition and Mitsuba 3's shapes without media. A null material (the
 * `null` BSDF, pbrt's `interface`) is no surface: paths and shadow rays cross it, changing
 * medium, and it counts as no vertex of the path (as in Mitsuba 3's volpath). */

/* The shadow rays of a path stop after this many null boundaries, counting the light as
 * unseen: only a scene that stacks more boundaries than this along one ray reaches it. */
#define MAX_NULL_CROSSINGS 64

/* The medium a ray is in after leaving surface s in direction w: the one on w's side of the
 * primitive's front (its geometric normal before a two-sided material turned it round:
 * Mitsuba 3's target_medium), or `current` where the primitive bounds no medium. */
int medium_after(const SceneData *sc, const Surface *s, float3 w, int current)
{
#ifdef GENERIC
    if (!(sc->layout & LAYOUT_MEDIA))
        return current;     /* a scene without media has no entry per primitive */
#endif
    int media = sc->prim_media[s->prim];
    if (media == NO_MEDIUM_CHANGE)
        return current;
    return (dot(w, s->ng) * s->side > 0.0f ? ((uint)media >> 16) : (media & 0xffff)) - 1;
}

/* Moves the ray *o + t d, which ends at *t_max and hit `hit`, on through the surface it hit:
 * its origin just beyond the surface, *t_max what is left of it, *self the surface; returns
 * the medium it is in beyond (`medium` where the surface bounds none). */
int cross_surface(const SceneData *sc, const Hit *hit, float3 *o, float3 d, float *t_max, PrimId *self, int medium)
{
    Surface s = surface_at(sc, hit, *o, d);
    float3 next = offset_ray_origin(s.p, s.offset, s.ng, d);
    *t_max -= dot(next - *o, d);
    *o = next;
    *self = HIT_ID(*hit);
    return medium_after(sc, &s, d, medium);
}

/* The fraction of radiance that reaches o from t_max away along unit direction d, the ray
 * starting in `medium` and leaving primitive `self`: the product of the media's
 * transmittances, each exact for a homogeneous medium, across null boundaries; 0 where a
 * surface is in the way. Without null surfaces (NULL_SURFACES) nothing changes the medium
 * along the way, and any surface blocks it: an any-hit query answers, as in scenes without
 * media, where finding the nearest hit is much slower (docs/notes/performance-2026-11.md, 2026-11-24:
 * participating media). */
float3 transmittance_along(const SceneData *sc, float3 o, float3 d, float t_max, PrimId self, int medium,
                           int *rays)
{
#ifndef NULL_SURFACES
    if (occluded(sc, o, d, t_max, self))
        return (float3)(0.0f);
    return medium >= 0 ? medium_transmittance(&sc->media[medium], t_max) : (float3)(1.0f);
#else
    float3 tr = (float3)(1.0f);
    for (int crossing = 0; crossing < MAX_NULL_CROSSINGS; ++crossing) {
        Hit hit = intersect_scene(sc, o, d, t_max, self);
        if (medium >= 0)
            tr *= medium_transmittance(&sc->media[medium], fmin(hit.t, t_max));
        if (hit.prim < 0)
            return tr;
        if (!(sc->materials[sc->prim_material[hit.prim]].flags & MATERIAL_NULL) || all(tr == 0.0f))
            return (float3)(0.0f);
        medium = cross_surface(sc, &hit, &o, d, &t_max, &self, medium);
        ++*rays;
    }
    return (float3)(0.0f);
#endif
}

/* The medium around point y (a light's): the one a ray from `eye`, starting in `medium` (the
 * camera's), is in on reaching it, changing medium at every primitive that bounds media on the
 * way, surfaces or not (a path from the camera to y would meet the same boundaries). pbrt-v4
 * gives a light the medium its file declares it in and Mitsuba 3 a point light's nested medium;
 * this finds the medium the boundaries say y is in, which both agree with wherever a file's
 * media are consistent. -1 past MAX_NULL_CROSSINGS boundaries. */
int medium_at(const SceneData *sc, float3 eye, int medium, float3 y, int *rays)
{
    float t_max = norm(y - eye);
    float3 d = (y - eye) / t_max, o = eye;
    t_max *= 1.0f - SHADOW_EPSILON;
    PrimId self = NO_PRIM;
    for (int crossing = 0; crossing < MAX_NULL_CROSSINGS; ++crossing) {
        ++*rays;
        Hit hit = intersect_scene(sc, o, d, t_max, self);
        if (hit.prim < 0)
            return medium;
        medium = cross_surface(sc, &hit, &o, d, &t_max, &self, medium);
    }
    return -1;
}
