/* Functions that CPUs must inline. PoCL's LLVM leaves large functions out of line, and a call
 * passes what its caller keeps in registers (a path's state, a hit's barycentric weights)
 * through memory: at every leaf of the traversal, for the triangle tests. NVIDIA's compiler
 * inlines those already (no call is left in the PTX of a textured pbrt-v4 scene's program), so
 * GPUs compile the form measured there (docs/performance.md, 2026-11-27). */

#ifndef PATHTRACE_INLINING_H
#define PATHTRACE_INLINING_H

#ifdef CPU_DEVICE
#define CPU_INLINE __attribute__((always_inline))
#else
#define CPU_INLINE
#endif

#endif
