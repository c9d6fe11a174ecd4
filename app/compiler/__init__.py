"""A scene compiled to the flat, device-independent tables the kernels read (compiled.py): the
BVH (bvh.py, built by each device's builder.py, or on the host by host_bvh.py), its cache on disk
(bvh_cache.py) and the compiled geometry's (geometry_cache.py), the two-level BVH of instanced
scenes (two_level.py), and the host-memory checks made before anything is allocated (memory.py)."""
