"""A scene compiled to the flat, device-independent tables the kernels read (compiled.py): the
BVH (bvh.py), its cache on disk (bvh_cache.py), the two-level BVH of instanced scenes
(two_level.py), and the host-memory checks made before anything is allocated (memory.py)."""
