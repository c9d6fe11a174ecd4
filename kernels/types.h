/* Structs shared by the host and the kernels. Each one is mirrored, field for field, by a NumPy
 * dtype in app/types.py; tests/test_types.py checks sizes and offsets on the device.
 * Only float4 and 4-byte scalars are used, so the layout is the same on every OpenCL device.
 *
 * Primitives have one index space, their BVH order: spheres are primitives [0, num_spheres),
 * triangles follow, triangle j being primitive num_spheres + j. Per-primitive tables
 * (material, light choice probability) are indexed by it. */

#ifndef PATHTRACE_TYPES_H
#define PATHTRACE_TYPES_H

/* A sphere: centre in xyz, radius in w. */
typedef float4 Sphere;

/* A triangle's corners in world space, counter-clockwise seen from its front (the geometric
 * normal is cross(v1 - v0, v2 - v0), as in Mitsuba 3). v0.w holds, as an int, the index of its
 * first of three per-corner shading normals in the normals table, or -1 when it has none. */
typedef struct {
    float4 v0;
    float4 v1;
    float4 v2;
} Triangle;

/* A material: a BSDF chosen by `type` (the BSDF_* tags of kernels/bsdf.cl) with up to twelve
 * parameters in p0..p2 (and a table, for those that tabulate one), whose meaning each
 * kernels/bsdfs/ file documents at its top, and the radiance its surface emits. */
typedef struct {
    float4 p0;
    float4 p1;
    float4 p2;
    float4 emission;  /* Le in rgb, emitted on the front side */
    int type;
    int flags;            /* MATERIAL_* bits of kernels/bsdf.cl */
    float continuation;   /* the report's Russian roulette: probability of going on from here */
    int pad0;
    float table[16];      /* a function of cos(theta) that a BSDF tabulates on the host, at
                             cos = (k / 15)^2 (app/materials/microfacet.py; lookup_cos_table) */
} Material;

/* A BVH node: up to four children, their boxes as structure-of-arrays so that one float4
 * operation tests all four. A leaf child holds spheres [index, index + count) when count > 0 and
 * triangles [index, index - count) when count < 0 (leaves hold one kind of shape); an inner
 * child has count == 0 and index its node; an unused slot has count 0, index -1 and a box at
 * +inf, which no ray enters. */
typedef struct {
    float4 lo_x, lo_y, lo_z, hi_x, hi_y, hi_z;
    int4 index;
    int4 count;
} BVHNode;

/* Everything one launch of the render kernel needs besides the scene buffers. */
typedef struct {
    float4 eye;        /* camera position */
    float4 forward;    /* unit view direction */
    float4 right;      /* camera right, scaled by tan(vfov / 2) * aspect */
    float4 up;         /* camera up, scaled by tan(vfov / 2) */
    float4 env_scale;  /* environment radiance multiplier (rgb) */
    int width;         /* image size in pixels */
    int height;
    uint sample_start; /* index of the first sample of this launch (keys the RNG) */
    uint sample_count; /* samples per pixel this launch */
    uint seed;
    int max_depth;     /* longest path in vertices (1: emitters seen directly); 0: unlimited */
    int env_width;
    int env_height;
    float env_rotation;  /* turn of the environment about +y, as a fraction of a full turn */
    int num_lights;      /* entries of the light table */
    float env_pick;      /* probability that next-event estimation samples the environment */
    int num_spheres;     /* the first triangle's primitive index */
    int rr_depth;        /* Russian roulette on throughput starts at this depth */
    int row_start;       /* the launch covers image rows [row_start, row_end): a band of a pass */
    int row_end;
    int pad3;
} RenderParams;

/* One entry of the light table: an emitter (a primitive, or the environment when prim is -1),
 * chosen in proportion to its power through Walker's alias method (Vose's construction):
 * entry i is kept when a uniform 32-bit word is below `keep` (a probability times 2^32), else
 * its `alias` is taken. `pick` is the overall probability of choosing this light. */
typedef struct {
    int prim;
    int alias;
    uint keep;
    float pick;
} Light;

#endif
