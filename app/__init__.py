"""pathtrace: an interactive, progressive path tracer with OpenCL kernels."""

__version__ = "0.1.0"
