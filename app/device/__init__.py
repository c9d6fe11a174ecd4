"""The device program and its assembly: OpenCL devices and the kernels' build with its binary
cache (opencl.py), what a scene needs of the kernels (features.py), the generic and the
specialised programs (programs.py), NVIDIA register caps (occupancy.py), and the NumPy mirrors
of kernels/types.h (types.py)."""
