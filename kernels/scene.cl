/* The compiled scene as the kernels see it (app/compiler/compiled.py builds it; app/rendering/renderer.py uploads
 * it): every table in one struct, so that helpers take one argument however the scene grows.
 * The order of the arguments is app/compiler/compiled.py's SCENE_BUFFERS. */

typedef struct {
    const global BVHNode *nodes;
    const global Sphere *spheres;           /* primitives [0, num_spheres), in BVH order */
    const global Triangle *triangles;       /* primitives [num_spheres, ...), in BVH order */
    const global float4 *normals;           /* per-corner shading normals of the triangles */
    const global float2 *uvs;               /* per-corner texture coordinates of the triangles */
    const global int *prim_material;        /* per primitive: its row of `materials` */
    const global Material *materials;
    const global TextureBinding *bindings;  /* the textured parameters of the materials */
    const global Texture *textures;
    const global uchar *texels;             /* the images of the textures, 4-byte aligned */
    const global float4 *env;               /* the environment map, rgba texels */
    const global Light *lights;
    const global float *light_pick;         /* per primitive: the probability that the light
                                               table chooses it (through a tree: the tree) */
    const global int *light_leaf;           /* per primitive: its leaf of the light tree */
    const global LightNode *light_nodes;    /* the light tree (kernels/light_tree.cl), if any */
    const global float *env_marginal;
    const global float *env_conditional;
    const global Medium *media;             /* the participating media (kernels/media/) */
    const global int *prim_media;           /* per primitive: the media it bounds
                                               (types.h: NO_MEDIUM_CHANGE) */
    const global Instance *instances;       /* a two-level BVH's instances (INSTANCES) */
    int num_spheres;
    int layout;                             /* LAYOUT_* bits, which a GENERIC program reads */
#ifdef TRAVERSAL_STATS
    int *work;                              /* the render kernels' count of traversal work:
                                               nodes visited (TRAVERSAL_STATS 1) or primitives
                                               tested (2); NULL in the other kernels */
#endif
#ifdef DIVERGENCE_STATS
    struct ShadingLog *shading_log;         /* the render kernels' record of their shading
                                               (kernels/divergence.cl); NULL in the others */
#endif
} SceneData;

/* Counts k units of traversal work where a kernel asked for them (app/bench/traversal_stats.py). */
#ifdef TRAVERSAL_STATS
#define COUNT_WORK(sc, kind, k) if ((kind) == TRAVERSAL_STATS && (sc)->work) *(sc)->work += (k)
#else
#define COUNT_WORK(sc, kind, k)
#endif
#define NODES_VISITED 1
#define PRIMITIVES_TESTED 2

#define SCENE_KERNEL_ARGS                                                                         \
    const global BVHNode *nodes, const global Sphere *spheres, const global Triangle *triangles,  \
    const global float4 *normals, const global float2 *uvs, const global int *prim_material,      \
    const global Material *materials, const global TextureBinding *bindings,                      \
    const global Texture *textures, const global uchar *texels, const global float4 *env,         \
    const global Light *lights, const global float *light_pick, const global int *light_leaf,    \
    const global LightNode *light_nodes, const global float *env_marginal,                        \
    const global float *env_conditional, const global Medium *media, const global int *prim_media, \
    const global Instance *instances

#define SCENE_DATA(num_spheres, layout)                                                           \
    {nodes, spheres, triangles, normals, uvs, prim_material, materials, bindings, textures,       \
     texels, env, lights, light_pick, light_leaf, light_nodes, env_marginal, env_conditional,      \
     media, prim_media, instances, num_spheres, layout}

/* How a compiled scene is laid out (app/compiler/compiled.py: CompiledScene.layout). A scene's own program
 * is built for its layout (LONE_SPHERES, INSTANCES, MEDIA); a GENERIC program, which renders any
 * scene, reads these bits instead. */
#define LAYOUT_LONE_SPHERES 1   /* the spheres are outside the BVH, which holds the triangles */
#define LAYOUT_INSTANCES 2      /* the BVH is a tree of instances (kernels/bvh.cl) */
#define LAYOUT_MEDIA 4          /* prim_media has an entry per primitive */
#define LAYOUT_LIGHT_TREE 8     /* lights are chosen through a light tree (kernels/light_tree.cl) */
#define LAYOUT_FLAT 16          /* a few primitives, tested all (kernels/bvh.cl: FLAT_SPHERES), */
#define LAYOUT_FLAT_TRIANGLES 8 /* the triangles' count in the bits from this one up */
#define LAYOUT_MASKS 32         /* a material has an opacity (kernels/masks.cl) */
#define LAYOUT_SHAPES 64        /* some primitives are analytic shapes (kernels/shapes/analytic.cl) */
/* A GENERIC program skips what a scene lacks by a test of its layout, the same for every ray,
 * before any work per primitive (docs/notes/performance-2026-11.md, 2026-11-29 seventh session);
 * a scene's own program has what it is built with. */
#ifdef GENERIC
#define HAS_LIGHT_TREE(sc) ((sc)->layout & LAYOUT_LIGHT_TREE)
#define HAS_MASKS(sc) ((sc)->layout & LAYOUT_MASKS)
#define HAS_SHAPES(sc) ((sc)->layout & LAYOUT_SHAPES)
#else
#define HAS_LIGHT_TREE(sc) 1    /* LIGHT_TREE is a scene's program's only where it has a tree */
#define HAS_MASKS(sc) 1         /* as ALPHA_MASKS */
#define HAS_SHAPES(sc) 1        /* as SHAPES */
#endif
