"""Shading sorted by material (the render setting path_sort, kernels/path_sort.cl): what the
Renderer (app/rendering/renderer.py), which is one, keeps and launches to sort its continuation
queue between the passes of continue_paths."""

import numpy as np
import pyopencl as cl

from pathtrace.device.types import PATH_RECORD

SORT_BUFFERS = ("keys", "keys_next", "order")   # an int per queue entry: the two queues' keys and
                                                # the sorted order of the queue a pass takes
SORT_GROUP = 256          # the work-items of sort_offsets' one work-group


class PathSort:
    """The Renderer's sorting of its queue (its buffers are allocated in Renderer._allocate_images)."""

    def sorts_queue(self) -> bool:
        """Whether launches sort the continuation queue's paths by material (settings.path_sort,
        kernels/path_sort.cl): only where they use the queue, so that "auto"'s plans without it and
        BDPT build no sort."""
        return bool(self.settings.path_sort) and self.queue_plan()[1]

    def record_bytes(self) -> int:
        """Bytes of a queue entry: PATH_RECORD, less its hit where launches do not sort."""
        return PATH_RECORD.itemsize - (0 if self.sorts_queue() else PATH_RECORD["hit"].itemsize)

    def sort_keys(self) -> int:
        """The keys by which path_sort sorts (kernels/path_sort.cl: sort_key): the environment and
        each material row."""
        return len(self.compiled.materials) + 1

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
