/* The continuation queue's records (PATH_QUEUE, the render setting path_queue;
 * kernels/integrator.cl: trace_path queues paths, continue_paths takes them on): where a path
 * waits between two of its vertices, as a structure of arrays. */

/* Where a path about to trace its ray to vertex `depth` waits instead: `records` holds
 * `capacity` paths, `count` counts those handed in (beyond capacity: not taken, they go on). With
 * PATH_SORT, keys[slot] is the sort key of the path in `slot` (kernels/path_sort.cl, its cells
 * of 2^shift primitives) and key_counts[key] counts the paths of each key. */
typedef struct {
    global float4 *records;
    volatile global int *count;
    int capacity;    /* 0: no queue */
    int depth;
#ifdef PATH_SORT
    global int *keys;
    volatile global int *key_counts;
    int shift;
#endif
} PathQueue;

/* A queue holds its paths as a structure of arrays: the k-th float4 of PathRecord for slot s at
 * records[k * capacity + s], so that the lanes of a warp storing or loading one field of
 * consecutive slots touch consecutive words (coalesced), where an array of 128-byte records had
 * each of the eight accesses touch 32 cache lines. Without MEDIA, `ratios` is neither stored nor
 * loaded. */
void store_path(global float4 *records, int capacity, int slot, const PathRecord *path)
{
    global float4 *r = records + slot;
    r[0] = path->o;
    r[capacity] = path->d;
    r[2 * capacity] = path->throughput;
    r[3 * capacity] = path->radiance;
    r[4 * capacity] = path->prev_x;
    r[5 * capacity] = path->prev_n;
#ifdef MEDIA
    r[6 * capacity] = path->ratios;
#endif
    r[7 * capacity] = as_float4(path->rng);
}

PathRecord load_path(const global float4 *records, int capacity, int slot)
{
    const global float4 *r = records + slot;
    PathRecord path;
    path.o = r[0];
    path.d = r[capacity];
    path.throughput = r[2 * capacity];
    path.radiance = r[3 * capacity];
    path.prev_x = r[4 * capacity];
    path.prev_n = r[5 * capacity];
#ifdef MEDIA
    path.ratios = r[6 * capacity];
#else
    path.ratios = (float4)(1.0f);
#endif
    path.rng = as_uint4(r[7 * capacity]);
    return path;
}

#ifdef PATH_QUEUE
/* Hands path r to the queue, with sort key `key` (PATH_SORT); returns whether it had room. */
int enqueue_path(PathQueue queue, const PathRecord *r, int key)
{
    int slot = atomic_inc(queue.count);
    if (slot >= queue.capacity)
        return 0;
    store_path(queue.records, queue.capacity, slot, r);
#ifdef PATH_SORT
    queue.keys[slot] = key;
    atomic_inc(&queue.key_counts[key]);
#endif
    return 1;
}
#endif
