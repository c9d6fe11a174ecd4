/* Shading sorted by material (PATH_SORT, the render setting path_sort; app/device/features.py):
 * the continuation queue's paths (kernels/integrator.cl, PATH_QUEUE) are traced to their next
 * hit before they wait, keyed by the material row they will shade there, and counting-sorted by
 * that key between the passes of continue_paths, so that the work-items of a warp, taking
 * consecutive entries of the sorted order, shade one material's code and parameters together
 * rather than each a different one with the other lanes masked off. `pathtrace bench
 * --divergence` measured why: on Bitterli's classroom a warp shaded 2.7 to 3 BSDF types and 6 to
 * 7 material rows each iteration, a shading SIMD efficiency of 0.29 (docs/notes/
 * performance-2026-11.md, 2026-11-29). This is the wavefront design of Laine, Karras and Aila
 * 2013 ("Megakernels Considered Harmful", HPG: a queue per material, whose kernel runs on full
 * warps), of pbrt-v4's wavefront integrator (src/pbrt/wavefront/intersect.h:
 * EnqueueWorkAfterIntersection pushes each hit to the queue of its material's type;
 * surfscatter.cpp: EvaluateMaterialsAndBSDFs runs one kernel per type over its queue) and of
 * Cycles (intern/cycles/integrator/path_trace_work_gpu.cpp: compute_sorted_queued_paths, "array
 * of active paths, sorted by shader", through which the shading kernel takes its paths). As
 * Cycles does, the records stay where they were written and only an index array is sorted. The
 * key is the material row, finer than pbrt-v4's type: rows of one type differ in parameters and
 * textures, and bench --divergence counted 6 to 7 rows against 3 types a warp. A path's result
 * does not depend on which work-item traces it, so the sorted queue renders the unsorted one's
 * samples.
 *
 * The counting sort, per queue: the kernel that queues a path stores its key beside it and
 * counts it (kernels/path_queue.cl: enqueue_path); sort_offsets turns the counts into the first
 * position of each key (an exclusive prefix sum); sort_paths writes each slot to the next
 * position of its key. The order within a key is that of the atomic increments, which changes no
 * result. Without the define none of this is compiled: the macros at the end are empty. */

#ifdef PATH_SORT

/* The key of a path whose ray hit primitive `prim` (-1: nothing): 0 for the environment, else
 * 1 + the material row it shades there (a blend's own row: the component it picks differs from
 * path to path). */
int sort_key(const SceneData *sc, int prim)
{
    return prim < 0 ? 0 : sc->prim_material[prim] + 1;
}

/* The hit that path r found before it waited (kernels/types.h: PathRecord.hit). */
Hit resumed_hit(const PathRecord *r)
{
    Hit h;
    h.t = r->hit.x;
    h.b1 = r->hit.y;
    h.b2 = r->hit.z;
    h.prim = as_int(r->prev_x.w);
    SET_INSTANCE(&h, as_int(r->prev_n.w));
    return h;
}

/* offsets[k] = the sum of counts[pass * num_keys + j] over j < k, for the num_keys keys of the
 * queue filled by pass `pass` (0: the render launch), in one work-group (app/rendering/renderer.py:
 * SORT_GROUP work-items, `runs` an int of local memory each): each work-item sums a run of keys,
 * one sums the runs' totals, each writes its run's offsets. */
kernel void sort_offsets(const global int *key_counts, int pass, int num_keys, global int *offsets,
                         local int *runs)
{
    const global int *counts = key_counts + pass * num_keys;
    int i = get_local_id(0), group = get_local_size(0), run = (num_keys + group - 1) / group;
    int first = min(i * run, num_keys), end = min(first + run, num_keys);
    int sum = 0;
    for (int k = first; k < end; ++k)
        sum += counts[k];
    runs[i] = sum;
    barrier(CLK_LOCAL_MEM_FENCE);
    if (i == 0) {
        int total = 0;
        for (int j = 0; j < group; ++j) {
            int n = runs[j];
            runs[j] = total;
            total += n;
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    sum = runs[i];
    for (int k = first; k < end; ++k) {
        offsets[k] = sum;
        sum += counts[k];
    }
}

/* One work-item per slot of the queue filled by pass `pass` (counters[pass] paths, at most
 * capacity): order[offsets[key]++] = slot. */
kernel void sort_paths(const global int *keys, const global int *counters, int pass, int capacity,
                       volatile global int *offsets, global int *order)
{
    int slot = get_global_id(0);
    if (slot < min(counters[pass], capacity))
        order[atomic_inc(&offsets[keys[slot]])] = slot;
}

/* The render kernels' arguments: the queue's keys, the counts of each pass's keys (num_keys
 * each, the render launch's first); continue_paths' also the order sort_paths wrote. */
#define SORT_KERNEL_ARGS , global int *keys, volatile global int *key_counts, int num_keys
#define CONTINUE_SORT_ARGS , const global int *order SORT_KERNEL_ARGS
#define SORT_QUEUE(pass) , keys, key_counts + (pass) * num_keys
#define QUEUE_SLOT(i) order[i]
#else
#define SORT_KERNEL_ARGS
#define CONTINUE_SORT_ARGS
#define SORT_QUEUE(pass)
#define QUEUE_SLOT(i) (i)
#endif
