/* Caustic photons (PHOTONS, a BDPT program's; pbrt-v4's "sppm" integrator asks for them): the
 * paths no strategy of BDPT samples but by chance, a surface seen through delta bounces alone and
 * lit through delta bounces alone (E S+ D S+ L: a pool's floor under its water, a table seen
 * through a glass of water), estimated by photon density estimation as progressive photon
 * mapping does (Hachisuka, Ogaki and Jensen, "Progressive photon mapping", 2008), with a radius
 * that shrinks with each pass so that its bias vanishes (Knaus and Zwicker, "Progressive photon
 * mapping: a probabilistic approach", 2011; app/rendering/photons.py).
 *
 * Each pass, one light subpath per pixel (kernels/bdpt.cl: trace_photons) leaves a photon where it
 * meets a surface that is not a delta after one or more delta bounces alone (L S+ D). Photons go
 * into a hashed grid of cells 2r wide, each cell a list linked through `next` from its head in
 * `heads`. A camera subpath gathers them where it meets such a surface after delta bounces alone
 * (E S+ D, the lens's own vertex aside), and its strategy s = 0 leaves out the paths of that form
 * that end on an emitter (bdpt.cl: connect_emitter), so that each path is counted once. "Delta"
 * is the lobe a vertex sampled (Vertex.delta), on either subpath. */

#ifdef PHOTONS
#define PHOTON_ARGS , global Photon *photons, global int *photon_next, global int *photon_heads, const PhotonMap map
#define PHOTONS_PASSED , photons, photon_next, photon_heads, &map
#else
#define PHOTON_ARGS
#define PHOTONS_PASSED
#endif

#ifdef PHOTONS
/* The grid cell (2r wide) of point x; cells beyond int's range are one cell (the distance test
 * sorts their photons out). */
int3 photon_cell(float3 x, float radius)
{
    return convert_int3_sat(floor(x / (2.0f * radius)));
}

/* The list a cell's photons are in (Teschner et al.'s spatial hash, 2003). */
uint photon_list(int3 cell, uint mask)
{
    return ((uint)cell.x * 73856093u ^ (uint)cell.y * 19349663u ^ (uint)cell.z * 83492791u) & mask;
}

/* The unit geometric normal of surface vertex v on the side of direction w. */
float3 normal_towards(const Vertex *v, float3 w)
{
    return dot(v->s.ng, w) < 0.0f ? -v->s.ng : v->s.ng;
}

/* Stores light subpath vertex k, v, its throughput times `weight`, as photon number *count
 * (counted up), at the head of its cell's list. */
void store_photon(global Photon *photons, global int *next, volatile global int *heads, volatile global int *count,
                  const PhotonMap *map, const Vertex *v, int k, float weight)
{
    int i = atomic_inc(count);
    Photon ph;
    ph.p = (float4)(v->s.p, (float)k);
    ph.beta = (float4)(v->beta * weight, 0.0f);
    ph.wo = (float4)(v->wo, 0.0f);
    ph.n = (float4)(normal_towards(v, v->wo), 0.0f);
    photons[i] = ph;
    next[i] = atomic_xchg(&heads[photon_list(photon_cell(v->s.p, map->radius), map->mask)], i);
}

/* The radiance camera vertex v (the subpath's j-th) sends back along v->wo from the photons within
 * the radius: sum of f(wo, wi_p) beta_p / (N pi r^2) over those on the same surface, either side
 * (the eight cells a disc of radius r about v can reach; a list two cells share read once) and
 * of light subpaths short enough that the joined path stays within the program's depth. */
float3 gather_photons(const SceneData *sc, const Vertex *v, int j, global const Photon *photons,
                      global const int *next, global const int *heads, const PhotonMap *map)
{
    float r = map->radius;
    int3 lo = photon_cell(v->s.p - r, r), hi = photon_cell(v->s.p + r, r);
    float3 n = normal_towards(v, v->wo), sum = (float3)(0.0f);
    uint read[8];
    int lists = 0;
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) {
                uint list = photon_list((int3)(x, y, z), map->mask);
                int again = 0;
                for (int i = 0; i < lists; ++i)
                    again |= read[i] == list;
                if (again)
                    continue;
                read[lists++] = list;
                for (int i = heads[list]; i >= 0; i = next[i]) {
                    Photon ph = photons[i];
                    float3 d = ph.p.xyz - v->s.p;
                    /* a surface at an angle (a corner's other wall) is not this one; its other
                       side is, where light arrives through a transmitting BSDF (an opaque one's
                       is 0 there) */
                    if (dot(d, d) > r * r || fabs(dot(ph.n.xyz, n)) < 0.5f || j + (int)ph.p.w > BDPT)
                        continue;
                    /* the photons' density is per area: the path tracer's |cos| with the shading
                       normal over the geometric normal's (Veach's correction at the last vertex) */
                    float cos_g = fabs(dot(ph.wo.xyz, v->s.ng));
                    if (cos_g > 0.0f)
                        sum += ph.beta.xyz * eval_scattering(sc, v, ph.wo.xyz, v->wo)
                               * (joined_cos(sc, v, ph.wo.xyz, v->wo, 0) / cos_g);
                }
            }
    return sum / ((float)map->paths * fmax(PI_F * r * r, FLT_MIN));     /* a radius too small to hold a square */
}

/* The photons' estimate along camera subpath cam (nc vertices) at each vertex j >= 2 that sees a
 * surface through delta bounces alone: the first vertex whose lobe is not a delta ends them. */
float3 caustic_radiance(const SceneData *sc, const Vertex *cam, int nc, global const Photon *photons,
                        global const int *next, global const int *heads, const PhotonMap *map)
{
    float3 l = (float3)(0.0f);
    for (int j = 1; j < nc && !in_medium(&cam[j]); ++j) {
        if (j >= 2 && cam[j].connectible)
            l += cam[j].beta * gather_photons(sc, &cam[j], j, photons, next, heads, map);
        if (!cam[j].delta)
            break;
    }
    return l;
}

/* Whether camera subpath cam, which ends on an emitter at vertex t - 1, has the form the photons
 * estimate (E S+ D S+ L, no vertex in a medium): one vertex j in [2, t - 3] whose lobe is not a
 * delta, a surface with more than a delta lobe, every other vertex's a delta. */
int photons_estimate(const Vertex *cam, int t)
{
    int j = 0;
    for (int k = 1; k < t - 1; ++k) {
        if (in_medium(&cam[k]))
            return 0;
        if (!cam[k].delta) {
            if (j)
                return 0;
            j = k;
        }
    }
    return j >= 2 && j <= t - 3 && cam[j].connectible;
}
#endif
