"""The continuation queue sorted by ray (the render setting path_sort, kernels/path_sort.cl): what
the Renderer (app/rendering/renderer.py), which is one, keeps and launches to sort its queue
between the passes of continue_paths."""

import math

import numpy as np
import pyopencl as cl

from pathtrace.device.features import SORT_CELLS, SORT_DIRECTIONS

SORT_BUFFERS = ("keys", "keys_next", "order")   # an int per queue entry: the two queues' keys and
                                                # the sorted order of the queue a pass takes
SORT_GROUP = 256          # the work-items of sort_offsets' one work-group


class PathSort:
    """The Renderer's sorting of its queue (its buffers are allocated in Renderer._allocate_images)."""

    def sorts_queue(self) -> bool:
        """Whether launches sort the continuation queue's paths by ray (settings.path_sort,
        kernels/path_sort.cl): only where they use the queue, so that "auto"'s plans without it and
        BDPT build no sort."""
        return bool(self.settings.path_sort) and self.queue_plan()[1]

    def sort_keys(self) -> int:
        """The keys by which path_sort sorts (kernels/path_sort.cl: sort_key): each direction bin's
        cells."""
        return SORT_DIRECTIONS * SORT_CELLS

    def sort_shift(self) -> int:
        """A key's cell holds 2^shift of the scene's tree-ordered primitives, so that they fill at
        most SORT_CELLS cells."""
        primitives = self.compiled.num_spheres + self.compiled.num_triangles
        return max(0, math.ceil(math.log2(max(primitives, 1) / SORT_CELLS)))

    def _sort_queue(self, k: int, keys: cl.Buffer, capacity, size: tuple, local: tuple) -> list:
        """Queues the counting sort of the queue that pass k takes (kernels/path_sort.cl): its keys'
        first positions from their counts, then the order of its slots by key, over `size`
        work-items in groups of `local`; returns the events."""
        b = self._buffers
        offsets, scatter = self.sort_kernels
        offsets.set_args(b["key_counts"], np.int32(k), np.int32(self.sort_keys()), b["offsets"],
                         cl.LocalMemory(4 * SORT_GROUP))
        scatter.set_args(keys, b["counters"], np.int32(k), capacity, b["offsets"], b["order"])
        return [cl.enqueue_nd_range_kernel(self.backend.queue, offsets, (SORT_GROUP,), (SORT_GROUP,)),
                cl.enqueue_nd_range_kernel(self.backend.queue, scatter, size, local)]
