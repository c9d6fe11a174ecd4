/* Structs shared by the host and the kernels. Each one is mirrored, field for field, by a NumPy
 * dtype in app/device/types.py; tests/test_types.py checks sizes and offsets on the device.
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
 * first of three per-corner shading normals in the normals table, or -1 when it has none; v1.w
 * likewise its first of three texture coordinates in the uvs table, or -1 (uv (0, 0)). */
typedef struct {
    float4 v0;
    float4 v1;
    float4 v2;
} Triangle;

/* A material: a BSDF chosen by `type` (the BSDF_* tags of kernels/bsdf.cl) with up to twelve
 * parameters in p0..p2 (and a table, for those that tabulate one or need more), which the
 * kernels read through the accessors <TYPE>_<NAME>(m) generated from the slots each type
 * declares on the host (app/materials/registry.py: tag_source), and the radiance its surface
 * emits. Parameters that
 * a texture gives are looked up at each hit (kernels/texture.cl: shade_material) and written
 * over their slots; the slots hold their mean, from which the host derives what the BSDF needs
 * as a constant (lobe choices, the light's power). */
typedef struct {
    float4 p0;
    float4 p1;
    float4 p2;
    float4 emission;  /* Le in rgb, emitted on the front side (both: MATERIAL_EMITS_BACK) */
    int type;
    int flags;            /* MATERIAL_* bits */
    float continuation;   /* the report's Russian roulette: probability of going on from here */
    int textures;         /* its first row of the texture bindings, or -1: none */
    float table[16];      /* more of the BSDF's slots: parameters that p0..p2 have no room
                             for, or a function of cos(theta) tabulated on the host */
} Material;

#define MATERIAL_TWOSIDED 1      /* the same BSDF on both sides (front-side frame mirrored) */
#define MATERIAL_DELTA 2         /* every lobe is a delta: no light sampling here */
#define MATERIAL_TRANSMISSIVE 4  /* an interface seen from both sides */
#define MATERIAL_MASKED 8        /* it has an opacity (kernels/masks.cl) */
#define MATERIAL_NULL 16         /* no surface, only a boundary between media (kernels/volume.cl) */
#define MATERIAL_EMITS_BACK 32   /* one surface emitting from both sides: pbrt-v4's DiffuseAreaLight
                                    with twoSided (lights.h, L: no test of the side) */
#define MATERIAL_PBRT_PERTURBATION 64   /* its normal or bump map perturbs as pbrt-v4's (normal_maps.cl) */

/* A parameter of a material that a texture gives: the texture's value at the hit goes into the
 * material's floats from `slot` on (p0.x is 0, p1.x 4, p2.x 8, emission.x 12). A material's
 * bindings are consecutive rows, the last one marked. */
typedef struct {
    int texture;   /* row of the texture table */
    int slot;
    int width;     /* 3: a colour, into slot .. slot + 2; 1: a number, the texture's luminance */
    int last;      /* 1 on the material's last binding */
} TextureBinding;

/* A texture: a function of the surface's uv (kernels/texture.cl), of the type `type` (the
 * TEXTURE_* tags, app/textures/registry.py), whose fields each kernels/textures/ file documents
 * at its top. Its inputs are numbered 0 to 2: input k is the texture of row input[k] where that is
 * >= 0 (one that combines none), the value in register -2 - input[k] of its program where that is
 * below -1 (one that combines others, kernels/texture.cl), else the constant value[k]. */
typedef struct {
    float4 to_u;       /* the uv transform: u' = dot(to_u.xyz, (u, v, 1)) */
    float4 to_v;       /* v' = dot(to_v.xyz, (u, v, 1)) */
    float4 value[3];
    int input[3];
    int type;
    int width;         /* an image's size in texels */
    int height;
    uint texels;       /* its first texel, in 4-byte words of the texel buffer */
    int format;        /* TEXELS_* of kernels/textures/bitmap.cl */
    int channels;      /* 1 or 4 (an rgb image is stored as rgba) */
    int wrap;          /* WRAP_* */
    int filter;        /* FILTER_* */
    int program;       /* a texture that combines others: its program's first row (kernels/texture.cl); -1 */
} Texture;

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

/* An instance of an object (app/scene/instances.py): the object's BVH below node `root`, seen
 * through the instance's transform, whose 3x4 rows (world from object) and its inverse's are
 * kept; the scene's own shapes are an instance of the identity. In a program for a scene
 * without a two-level BVH (INSTANCES), the table is one unread row. */
typedef struct {
    float4 to_world[3];
    float4 to_object[3];
    int root;
    int pad[3];
} Instance;

/* Everything one launch of the render kernel needs besides the scene buffers. */
typedef struct {
    float4 eye;        /* camera position */
    float4 forward;    /* unit view direction */
    float4 right;      /* the image's right and up, as the camera type scales them */
    float4 up;         /* (app/cameras/: Camera.basis; kernels/cameras/<name>.cl) */
    float4 env_scale;  /* environment radiance multiplier (rgb) */
    float4 lens;       /* what else the camera type reads (app/cameras/: Camera.lens) */
    float4 filter;     /* the pixel filter's parameters (kernels/filters/<name>.cl) */
    float4 world;      /* the scene's bounding sphere: centre (xyz) and radius (w) */
    float4 env_frame[3];   /* rows of the rotation from world directions to the map's own */
    int width;         /* image size in pixels */
    int height;
    uint sample_start; /* index of the first sample of this launch (keys the RNG) */
    uint sample_count; /* samples per pixel this launch */
    uint seed;
    int max_depth;     /* longest path in vertices (1: emitters seen directly); 0: unlimited */
    int env_width;
    int env_height;
    float env_row_scale; /* the map's row, in texels, at v = acos(y) / pi: v * env_row_scale + env_row_offset */
    float env_row_offset;  /* (app/scene/environment.py: Environment.row_mapping) */
    int num_lights;      /* entries of the light table */
    float env_pick;      /* probability that next-event estimation samples the environment */
    int num_spheres;     /* the first triangle's primitive index */
    int rr_depth;        /* Russian roulette on throughput starts at this depth */
    int row_start;       /* the launch covers image rows [row_start, row_end): a band of a pass */
    int row_end;
    int camera_medium;   /* the medium the camera is in (a row of the media table), or -1 */
    /* What a GENERIC program (app/device/features.py: Features.generic_program) chooses at run time, and a
       scene's program by build options: */
    int camera_type;     /* the camera's kernel (app/cameras/registry.py: KERNELS index) */
    int filter_type;     /* the pixel filter (app/filters.py: FILTERS index) */
    int rr_rule;         /* Russian roulette's rule (RR_OFF, RR_ALBEDO, RR_THROUGHPUT) */
    int layout;          /* the compiled scene's LAYOUT_* bits (kernels/scene.cl) */
    int pad[3];          /* to the float4s' alignment, which the struct has anyway */
} RenderParams;

/* One entry of the light table: a light of type `type` (the LIGHT_* tags of
 * app/lights/registry.py) whose values lie in p0..p2 in the slots its host declares, read
 * through the accessors <NAME>_LIGHT_<SLOT>(l) generated from them (app/device/slots.py); an area light names its emissive primitive (`prim`, else -1). Lights are chosen in
 * proportion to power through Walker's alias method (Vose's construction): entry i is kept when
 * a uniform 32-bit word is below `keep` (a probability times 2^32), else its `alias` is taken.
 * `pick` is the overall probability of choosing this light. */
typedef struct {
    uint keep;
    int alias;
    float pick;
    int type;
    int prim;
    int pad[3];
    float4 p0;
    float4 p1;
    float4 p2;
} Light;

/* A node of the light tree (app/lights/tree.py): the root is node 0; a leaf is one light. */
typedef struct {
    float4 lo;      /* xyz: its lights' box's low corner; w: their total power */
    float4 hi;      /* xyz: the box's high corner; w: cos(theta_o), the spread of their normals */
    float4 axis;    /* xyz: the normals' cone's axis; w: cos(theta_e), how far beyond its normal
                       each light emits */
    int child;      /* its first child (the second follows it), or -1 for a leaf */
    int parent;     /* -1 for the root */
    int light;      /* a leaf's entry of the light table */
    int pad;
} LightNode;

/* A path between two of its vertices, waiting in the continuation queue (kernels/integrator.cl,
 * PATH_QUEUE): trace_path's loop state, with integers in float slots as their bits. */
typedef struct {
    float4 o;           /* xyz: the ray's origin; w: eta_scale */
    float4 d;           /* xyz: its direction; w: pdf_prev */
    float4 throughput;  /* xyz; w: the depth of the vertex the ray is to find */
    float4 radiance;    /* xyz: what has reached the camera so far; w: the medium the ray crosses */
    float4 prev_x;      /* xyz: the vertex it left; w: the primitive it left */
    float4 prev_n;      /* xyz: the normal there; w: the instance that draws that primitive */
    float4 ratios;      /* with MEDIA, xyz: the channels' path densities over the hero's; w: the hero */
    uint4 rng;          /* its random numbers' key: pixel x, y, sample; w: the dimensions drawn */
} PathRecord;

/* A participating medium (kernels/media/homogeneous.cl documents its fields): homogeneous,
 * with a Henyey-Greenstein phase function (kernels/phase.cl). */
typedef struct {
    float4 sigma_s;   /* scattering coefficient per unit length (rgb); w: the phase function's g */
    float4 sigma_t;   /* extinction coefficient sigma_a + sigma_s (rgb); w unused */
} Medium;

/* A caustic photon (kernels/photons.cl): where a light subpath met a surface that is not a
 * delta after delta bounces alone (one such surface chosen, where it met several). */
typedef struct {
    float4 p;        /* xyz: the point; w: its vertex's index on the light subpath (2 or more) */
    float4 beta;     /* xyz: the light subpath's throughput there (its flux times the subpaths
                        of the pass) */
    float4 wo;       /* xyz: the unit direction back along the subpath */
    float4 n;        /* xyz: the surface's unit geometric normal, on wo's side */
} Photon;

/* A pass's photon map: its gather radius, the light subpaths traced, and the mask of its grid's
 * hash (a power of two less one; photons.cl). */
typedef struct {
    float radius;
    int paths;
    uint mask;
    int pad;
} PhotonMap;

/* A primitive's media (scene.cl: prim_media): NO_MEDIUM_CHANGE where crossing or leaving it
 * keeps the medium a ray is in, else (interior + 1) | (exterior + 1) << 16, a row of the media
 * table on each side, 0 standing for none (vacuum). */
#define NO_MEDIUM_CHANGE (-1)

#endif
