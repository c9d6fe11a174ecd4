/* The continuation queue sorted by ray (PATH_SORT, the render setting path_sort;
 * app/device/features.py): the queue's paths (kernels/integrator.cl, PATH_QUEUE) wait before
 * they trace their next ray, keyed by that ray, and are counting-sorted by key between the passes
 * of continue_paths, so that the work-items of a warp, taking consecutive entries of the sorted
 * order, trace rays that start near one another in like directions: their walks through the BVH
 * visit the same nodes, loaded once for the warp, and end after like numbers of steps. The key
 * is the ray's direction bin (24: the cube face of its largest component, and the quadrant
 * within the face) and the primitive it leaves, whose index in the tree's order (the builder
 * orders them so) is a place in the scene, in SORT_CELLS cells of 2^shift primitives. This is
 * the ray reordering of Pharr et al. 1997 ("Rendering Complex Scenes with Memory-Coherent Ray
 * Tracing") and of Garanzha and Loop 2010 (rays binned by origin and direction before a GPU
 * traces them), in the queue of a wavefront (Laine, Karras and Aila 2013, "Megakernels
 * Considered Harmful"). A first form keyed the queue by the material each path would shade next
 * (pbrt-v4's and Cycles' wavefronts): its warps shaded one material, but on the H200 the
 * classroom's renders took 3 % longer than the megakernel's, where keyed by ray they take 15 %
 * less (docs/notes/performance-2026-11.md, 2026-11-30, eighteenth session). A path's result does
 * not depend on which work-item traces it, so the sorted queue renders the unsorted one's
 * samples.
 *
 * The counting sort, per queue: the kernel that queues a path stores its key beside it and
 * counts it (kernels/path_queue.cl: enqueue_path); sort_offsets turns the counts into the first
 * position of each key (an exclusive prefix sum); sort_paths writes each slot to the next
 * position of its key. The order within a key is that of the atomic increments, which changes no
 * result. Without the define none of this is compiled: the macros at the end are empty. */

#ifdef PATH_SORT

#if SORT_DIRECTIONS != 24
#error "sort_key makes 24 direction bins, for which the host sizes its counts (app/device/features.py)"
#endif

/* The key of a ray of direction d leaving primitive `self` (NO_PRIM: none, in cell 0) of a scene
 * whose tree-ordered primitives fall in cells of 2^shift (app/rendering/path_sort.py:
 * sort_shift): its direction bin (of SORT_DIRECTIONS) times SORT_CELLS + its cell (both build
 * options: app/device/features.py). A NaN direction falls in a bin like any other. */
int sort_key(int shift, float3 d, PrimId self)
{
    float3 a = fabs(d);
    int axis = a.x >= a.y && a.x >= a.z ? 0 : a.y >= a.z ? 1 : 2;
    float major = axis == 0 ? d.x : axis == 1 ? d.y : d.z;
    float u = axis == 0 ? d.y : d.x, v = axis == 2 ? d.y : d.z;
    int direction = (2 * axis + (major < 0.0f)) * 4 + (u < 0.0f) + 2 * (v < 0.0f);
    int prim = PRIM_ID_PAIR(self).x;
    return direction * SORT_CELLS + (prim < 0 ? 0 : min(prim >> shift, SORT_CELLS - 1));
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
 * each, the render launch's first), the keys' cell size (sort_key); continue_paths' also the
 * order sort_paths wrote. */
#define SORT_KERNEL_ARGS , global int *keys, volatile global int *key_counts, int num_keys, int sort_shift
#define CONTINUE_SORT_ARGS , const global int *order SORT_KERNEL_ARGS
#define SORT_QUEUE(pass) , keys, key_counts + (pass) * num_keys, sort_shift
#define QUEUE_SLOT(i) order[i]
#define QUEUE_KEY(queue, d, self) sort_key((queue).shift, d, self)
#else
#define SORT_KERNEL_ARGS
#define CONTINUE_SORT_ARGS
#define SORT_QUEUE(pass)
#define QUEUE_SLOT(i) (i)
#define QUEUE_KEY(queue, d, self) 0
#endif
