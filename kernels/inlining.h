/* Functions that CPUs must inline. PoCL's LLVM leaves large functions out of line, and a call
 * passes what its caller keeps in registers (a path's state, a hit's barycentric weights)
 * through memory: at every leaf of the traversal, for the triangle tests. NVIDIA's compiler
 * inlines those already (no call is left in the PTX of a textured pbrt-v4 scene's program), so
 * GPUs compile the form measured there (docs/notes/performance-2026-11.md, 2026-11-27). */

#ifndef PATHTRACE_INLINING_H
#define PATHTRACE_INLINING_H

#ifdef CPU_DEVICE
#define CPU_INLINE __attribute__((always_inline))
#else
#define CPU_INLINE
#endif

/* The dispatch over every kind of BSDF, texture and light, in a generic program on a GPU, is
 * called rather than inlined: NVIDIA's compiler inlined every kind into each of its call sites
 * in every kernel, a program that took its driver minutes to build (docs/notes/performance-2026-11.md,
 * 2026-11-28 evening). But for the textures that read no other (eval_leaf_texture,
 * app/textures/registry.py: called, NVIDIA's driver 580 built a program that miscounted), and
 * the commonest BSDF and light (FAST_PATH of app/materials/registry.py and app/lights/registry.py),
 * tested before the call and inlined, so that most scenes' vertices make no call
 * (docs/notes/performance-2026-11.md, 2026-11-30, seventeenth session). A
 * scene's own program, which compiles only its kinds, and CPUs, whose calls pass a path's state
 * through memory, keep them inlined.
 * The analytic shapes' functions (kernels/shapes/analytic.cl) and the alpha masks' (kernels/masks.cl)
 * are called in a generic program on a GPU too: inlined, they sat in the BVH walk's leaf loop and
 * in the shading of every scene, which paid in registers for what most scenes lack (the layout's
 * bits skip them at run time, not at compile time); called, with the leaf loop of a scene without
 * either holding the triangle test alone (kernels/bvh.cl), a scene without them renders a fifth
 * faster (docs/notes/performance-2026-12.md, 2026-12-03, thirtieth session). */
#if defined(GENERIC) && !defined(CPU_DEVICE)
#define DISPATCH __attribute__((noinline))
#else
#define DISPATCH
#endif

#endif
