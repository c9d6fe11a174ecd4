/* Structs shared by the host and the kernels. Each one is mirrored, field for field, by a NumPy
 * dtype in app/types.py; tests/test_types.py checks sizes and offsets on the device.
 * Only float4 and 4-byte scalars are used, so the layout is the same on every OpenCL device. */

#ifndef PATHTRACE_TYPES_H
#define PATHTRACE_TYPES_H

/* A sphere: centre in xyz, radius in w. */
typedef float4 Sphere;

/* The modified Phong BRDF of Lafortune & Willems (1994) plus emission.
 * f = rho_d / pi + rho_s (n + 2) / (2 pi) cos^n(theta_r). */
typedef struct {
    float4 diffuse;   /* rho_d in rgb; w: probability of choosing the diffuse lobe */
    float4 specular;  /* rho_s in rgb; w: the Phong exponent n */
    float4 emission;  /* Le in rgb; w: probability of choosing the glossy lobe */
} Material;

/* One child of a BVH node: its box and what it holds. A leaf has count > 0 and holds spheres
 * [index, index + count); an inner child has count == 0 and index is its node. Keeping both
 * children's boxes in the parent lets traversal test them together and go nearer-first. */
typedef struct {
    float lo[3];
    int index;
    float hi[3];
    int count;
} BVHChild;

typedef struct {
    BVHChild child[2];
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
    int russian_roulette;
    int env_width;
    int env_height;
    float env_rotation;  /* turn of the environment about +y, as a fraction of a full turn */
    int num_lights;      /* entries of the light table */
    float env_pick;      /* probability that next-event estimation samples the environment */
    int pad0;
    int pad1;
    int pad2;
    int pad3;
} RenderParams;

/* One entry of the light table: an emissive sphere, chosen in proportion to its power through
 * Walker's alias method (Vose's construction): entry i is kept with probability `keep`, else
 * its `alias` is taken. `pick` is the overall probability of choosing this light. */
typedef struct {
    int sphere;
    int alias;
    float keep;
    float pick;
} Light;

#endif
