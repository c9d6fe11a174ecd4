/* The divergence stats build (DIVERGENCE_STATS, app/device/features.py; read by
 * app/bench/divergence_stats.py): the render kernels record, for each iteration of the path
 * tracer's loop (kernels/integrator.cl: trace_path, one ray traced per iteration) and each
 * work-item, what shading the iteration did, so that the host can ask how many lanes of a warp
 * run each branch while the warp runs it. DIVERGENCE_STATS is the number of iterations recorded
 * per path; later ones are not. Without the define none of this is compiled: the macros at the
 * end are empty, and a program that does not count pays nothing.
 *
 * Records: one byte per (sample of the launch, iteration, field, work-item), the work-items
 * innermost, in the order in which GPUs form warps (log_lane), so that the host reads each warp's
 * lanes as consecutive bytes. The buffer is zeroed before each launch: 0 is an idle lane. In the
 * continuation queue's kernels (PATH_QUEUE: continue_paths) a work-item is a queue entry, taken
 * in the order that its 1-D work-groups form warps, and each pass records into a buffer of its
 * own, as one sample whose iterations are numbered from the camera ray as the megakernel's are
 * (LOG_RESUME). */

#ifdef DIVERGENCE_STATS

/* The fields, each one byte (app/bench/divergence_stats.py: FIELDS) */
#define LOG_SHADING 0      /* the SHADING_* code of what the iteration did after tracing its ray */
#define LOG_TEXTURES 1     /* the image texture lookups it made (eval_bitmap and grad_bitmap
                              calls, opacity masks on its rays' way included), at most 255 */
#define LOG_LIGHT 2        /* 1 + the LIGHT_* type of the light its next-event estimation sampled
                              (LIGHT_TREE_ROOT where a light tree chose none); 0: none sampled */
#define LOG_MATERIAL 3     /* with the next field, the low and high bytes of 1 + the material row
                              of the surface it shaded (a blend's own row; at most 65535); 0: none */
#define LOG_FIELDS 5

/* The shading codes (app/bench/divergence_stats.py: SHADING_NAMES) */
#define SHADING_IDLE 0          /* did nothing: its path had ended */
#define SHADING_TRACED 1        /* traced its ray and ended without shading (a medium's
                                   scattering at the last vertex) */
#define SHADING_ESCAPED 2       /* met nothing: the environment is looked up */
#define SHADING_LAST_VERTEX 3   /* the path's last vertex, or a back face that scatters nothing:
                                   its emission alone, no BSDF */
#define SHADING_NULL 4          /* a null surface, crossed */
#define SHADING_MEDIUM 5        /* scattered in a medium: the phase function */
#define SHADING_BSDF 6          /* a surface shaded: SHADING_BSDF + its BSDF_* tag */

struct ShadingLog {
    global uchar *records;
    int sample;        /* the launch's sample under way */
    int iteration;     /* the loop's iteration under way, from 0 (-1 before the first) */
};

/* The work-item's place in warp order: its work-group's, then its linear local id (x fastest).
 * NVIDIA's GPUs cut a block into warps of consecutive thread ids, x fastest (CUDA C++
 * Programming Guide, "SIMT Architecture" and "Thread Hierarchy"), AMD's into wavefronts alike. */
size_t log_lane(void)
{
    size_t group = get_group_id(1) * get_num_groups(0) + get_group_id(0);
    return group * get_local_size(0) * get_local_size(1) + get_local_id(1) * get_local_size(0)
           + get_local_id(0);
}

/* The byte of `field` for the work-item's current iteration, or NULL outside a recorded
 * iteration (or in a kernel that records nothing: sc->shading_log NULL). */
global uchar *log_record(const SceneData *sc, int field)
{
    const struct ShadingLog *l = sc->shading_log;
    if (!l || l->iteration < 0 || l->iteration >= DIVERGENCE_STATS)
        return 0;
    size_t lanes = get_global_size(0) * get_global_size(1);
    size_t row = ((size_t)l->sample * DIVERGENCE_STATS + l->iteration) * LOG_FIELDS + field;
    return l->records + row * lanes + log_lane();
}

void log_value(const SceneData *sc, int field, int value)
{
    global uchar *r = log_record(sc, field);
    if (r)
        *r = (uchar)value;
}

/* The surface of primitive `prim` is shaded with its BSDF of tag `type`. */
void log_bsdf(const SceneData *sc, int prim, int type)
{
    log_value(sc, LOG_SHADING, SHADING_BSDF + type);
    int row = min(sc->prim_material[prim] + 1, 65535);
    log_value(sc, LOG_MATERIAL, row & 255);
    log_value(sc, LOG_MATERIAL + 1, row >> 8);
}

/* The next iteration of the loop begins: the work-item traces its ray (SHADING_TRACED until
 * what follows says more). */
void log_iteration(const SceneData *sc)
{
    if (sc->shading_log) {
        ++sc->shading_log->iteration;
        log_value(sc, LOG_SHADING, SHADING_TRACED);
    }
}

void log_texture_lookup(const SceneData *sc)
{
    global uchar *r = log_record(sc, LOG_TEXTURES);
    if (r && *r < 255)
        ++*r;
}

#define LOG_KERNEL_ARG , global uchar *shading_records
#define LOG_SHADING_INTO(sc) struct ShadingLog log_ = {shading_records, 0, -1}; (sc).shading_log = &log_
#define LOG_SAMPLE(sc, i) if ((sc)->shading_log) { (sc)->shading_log->sample = (i); (sc)->shading_log->iteration = -1; }
#define LOG_ITERATION(sc) log_iteration(sc)
/* a path taken from the continuation queue: its next iteration is `next` */
#define LOG_RESUME(sc, next) if ((sc)->shading_log) { (sc)->shading_log->iteration = (next) - 1; }
#define LOG_SHADED(sc, code) log_value(sc, LOG_SHADING, code)
#define LOG_BSDF(sc, prim, type) log_bsdf(sc, prim, type)
#define LOG_LIGHT_SAMPLED(sc, ls) \
    log_value(sc, LOG_LIGHT, 1 + ((ls).light >= 0 ? (sc)->lights[(ls).light].type : LIGHT_TREE_ROOT))
#define LOG_TEXTURE_LOOKUP(sc) log_texture_lookup(sc)
#else
#define LOG_KERNEL_ARG
#define LOG_SHADING_INTO(sc)
#define LOG_SAMPLE(sc, i)
#define LOG_ITERATION(sc)
#define LOG_RESUME(sc, next)
#define LOG_SHADED(sc, code)
#define LOG_BSDF(sc, prim, type)
#define LOG_LIGHT_SAMPLED(sc, ls)
#define LOG_TEXTURE_LOOKUP(sc)
#endif
