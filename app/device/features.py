"""What a scene needs of the kernels: the device-independent key by which app/device/opencl.py
specialises the kernel program to a scene."""

from dataclasses import dataclass

GENERIC = "generic"
"""The camera, filter and Russian roulette rule of a generic program (Features.generic_program), which
chooses them at run time."""
SORT_DIRECTIONS = 24      # with path_sort, a ray's key: its direction's bin (kernels/path_sort.cl)
SORT_CELLS = 2048         # and the cell of the tree-ordered primitive it leaves

KERNEL_SETS = {"all": ("ENTRY_RENDER", "ENTRY_RENDER_NEE", "ENTRY_AUX"), "render": ("ENTRY_RENDER",),
               "render_nee": ("ENTRY_RENDER_NEE",), "aux": ("ENTRY_AUX",), "bdpt": ()}
"""Which entry points a program holds (Features.kernels), by the defines that compile them in
(kernels/integrator.cl, kernels/aovs.cl): a path tracer's pass launches one render kernel, by
its estimator (render, or render_nee with next-event estimation, each with its continuation
queue's kernels where it has a queue); the auxiliary kernels, render_aovs (the denoiser's albedo
and normal) and pick (the viewer's), are launched by some renders only; BDPT's kernels come with
its files (BDPT). A scene's own program holds what its passes launch and nothing more: on an
H200 the program with both render kernels, the AOVs and pick built in 1.7-2.4 s, render_nee
alone in 1.0-1.5 s (docs/notes/performance-2026-11.md, 2026-11-30, sixteenth session), and
a first start waits for that build. The generic programs hold them all, as do the viewer's
(Renderer's all_kernels: a user may turn next-event estimation, the denoiser or picking on at
any moment, and none of them should wait for a build)."""


@dataclass(frozen=True)
class Features:
    """What a scene and its settings need of the kernels. Each scene's program is specialised
    to it and leaves out the code of the shapes, materials and Russian roulette rule it does
    not use (and only its lights' types, its camera and its pixel filter, and the volumetric
    paths only where it has media): on a GPU every branch a kernel could take costs registers, hence occupancy, in
    every thread (docs/performance.md). The default, every shape and material and no textures,
    is the program the tests build their kernels beside."""
    spheres: bool = True                   # the scene has spheres (else NO_SPHERES: no sphere test)
    triangles: bool = True                 # the scene has triangles (else NO_TRIANGLES)
    shapes: tuple = ()                     # the analytic shape kinds it has (pathtrace.shapes.SHAPES;
                                           # SHAPES, kernels/shapes/analytic.cl); () leaves them out
    bsdfs: tuple = None                    # names of pathtrace.materials.BSDFS; None: all of them
    textures: tuple = ()                   # names of pathtrace.textures.TEXTURES the scene uses;
                                           # () leaves all texture code out
    masks: bool = False                    # a material has an opacity (kernels/masks.cl)
    normal_maps: bool = False              # a material has a normal or bump map (kernels/normal_maps.cl)
    lights: tuple = None                   # the delta light types the scene has (pathtrace.lights.
                                           # DELTA_LIGHTS; area lights and the environment are
                                           # always compiled in); None: all
    light_tree: bool = False               # lights are chosen through a light tree (kernels/light_tree.cl)
    media: bool = False                    # participating media or null surfaces (kernels/volume.cl)
    null_surfaces: bool = False            # a material is null: rays cross it (NULL_SURFACES)
    camera: str = "perspective"            # its kernel file: pathtrace.cameras.Camera.kernel
    filter: str = "box"                    # one of pathtrace.filters.FILTERS
    russian_roulette: str = "throughput"   # one of pathtrace.scene.description.RUSSIAN_ROULETTE
    instances: bool = False                # a two-level BVH (INSTANCES): a tree over instances of
                                           # objects' trees
    flat: tuple = ()                       # (spheres, triangles) of a scene of at most FLAT_MAX
                                           # primitives, which rays test all, with no tree
    lone_spheres: int = 0                  # the spheres of a scene of triangles and at most LONE_MAX
                                           # of them, which rays test before walking a tree over the
                                           # triangles alone (LONE_SPHERES, kernels/bvh.cl); 0: none
    bsdf_defines: tuple = None             # the variants its materials need (BSDFType.defines,
                                           # such as BECKMANN); None: all
    traversal_stats: int = 0               # 1 or 2: the render kernels count nodes visited or
                                           # primitives tested in place of rays
                                           # (app/bench/traversal_stats.py); 0: they count rays
    divergence_stats: int = 0              # the render kernels record their shading for this many
                                           # iterations of each path (DIVERGENCE_STATS,
                                           # kernels/divergence.cl; app/bench/divergence_stats.py);
                                           # 0: they record nothing
    path_queue: int = 0                    # paths going on past this many vertices wait in the
                                           # continuation queue (PATH_QUEUE, kernels/integrator.cl;
                                           # the render setting path_queue); 0: no queue
    path_sort: bool = False                # with path_queue: the queue's paths are sorted by the
                                           # ray they trace next (PATH_SORT,
                                           # kernels/path_sort.cl; the render setting path_sort)
    bdpt: int = 0                          # bidirectional path tracing (kernels/bdpt.cl) of paths
                                           # up to this depth (app/rendering/bdpt.py); 0: the path tracer alone
    light_tracing: bool = False            # with bdpt: light tracing alone (LIGHT_TRACING), the
                                           # integrator "ptracer"
    photons: bool = False                  # with bdpt: caustic photons (PHOTONS, kernels/photons.cl)
    generic: bool = False                  # renders any scene (Features.generic_program)
    kernels: str = "all"                   # the entry points it holds: a key of KERNEL_SETS

    @staticmethod
    def generic_program(media: bool) -> "Features":
        """A program that renders every scene pathtrace can load, with every shape, BSDF,
        texture, light and medium compiled in and the camera, pixel filter, Russian roulette
        rule and the compiled scene's layout (kernels/scene.cl: LAYOUT_*) read from the launch's
        RenderParams (GENERIC). Built once per device and driver and cached, it draws a scene's
        first images while the scene's own program, specialised by these features, builds
        (pathtrace.device.programs). There are two: with participating media and null surfaces
        (`media`) and without, for the scenes that have neither, whose paths the volumetric
        code slowed by 21-50 % on an H200 (docs/notes/performance-2026-11.md, 2026-11-29: the
        generic program's ablation)."""
        from pathtrace.shapes import SHAPES
        from pathtrace.textures import TEXTURES
        return Features(shapes=tuple(SHAPES), textures=tuple(TEXTURES), masks=True, normal_maps=True, light_tree=True,
                        media=media, null_surfaces=media, camera=GENERIC, filter=GENERIC,
                        russian_roulette=GENERIC, instances=True, generic=True)

    def defines(self) -> tuple:
        return ((() if self.spheres else ("NO_SPHERES",)) + (() if self.triangles else ("NO_TRIANGLES",))
                + (("SHAPES",) if self.shapes else ())
                + (("TEXTURES",) if self.textures else ())
                + (("ALPHA_MASKS",) if self.masks else ()) + (("NORMAL_MAPS",) if self.normal_maps else ())
                + (("LIGHT_TREE",) if self.light_tree else ()) + (("MEDIA",) if self.media else ())
                + (("NULL_SURFACES",) if self.null_surfaces else ())
                + (("GENERIC",) if self.generic else (f"RUSSIAN_ROULETTE=RR_{self.russian_roulette.upper()}",))
                + ((f"FLAT_SPHERES={self.flat[0]}", f"FLAT_TRIANGLES={self.flat[1]}") if self.flat else ())
                + ((f"LONE_SPHERES={self.lone_spheres}",) if self.lone_spheres else ())
                + (("INSTANCES",) if self.instances else ())
                + (self.bsdf_defines if self.bsdf_defines is not None else all_bsdf_defines())
                + ((f"TRAVERSAL_STATS={self.traversal_stats}",) if self.traversal_stats else ())
                + ((f"DIVERGENCE_STATS={self.divergence_stats}",) if self.divergence_stats else ())
                + ((f"PATH_QUEUE={self.path_queue}",) if self.path_queue else ())
                + (("PATH_SORT", f"SORT_DIRECTIONS={SORT_DIRECTIONS}", f"SORT_CELLS={SORT_CELLS}")
                   if self.path_sort else ())
                + ((f"BDPT={self.bdpt}",) if self.bdpt else ()) + (("LIGHT_TRACING",) if self.light_tracing else ())
                + (("PHOTONS",) if self.photons else ()) + KERNEL_SETS[self.kernels])


def choice_glue(signature: str, call: str, names: tuple, chosen: str, field: str) -> str:
    """The kernel function `signature` that returns `call` (a format of one kind's name) for
    the kind `chosen` of `names`, or in a generic program (chosen GENERIC) for the kind whose
    index in `names` the launch's RenderParams field `field` holds."""
    if chosen != GENERIC:
        return f"{signature}\n{{\n    return {call.format(chosen)};\n}}\n"
    cases = "".join(f"    case {i}: return {call.format(n)};\n" for i, n in enumerate(names[:-1]))
    return (f"{signature}\n{{\n    switch (p->{field}) {{\n{cases}"
            f"    default: return {call.format(names[-1])};\n    }}\n}}\n")


def all_bsdf_defines() -> tuple:
    from pathtrace.materials import BSDFS
    return tuple(sorted({d for b in BSDFS.values() for d in b.variant_defines}))


FLAT_MAX = 8
"""The most primitives a scene may have for its rays to test them all instead of traversing its
BVH (kernels/bvh.cl). The counts are compile-time constants, so the tests unroll: for a handful
of spheres that is cheaper than a traversal's node loads, sort and stack, and leaves the
kernel fewer registers, hence more threads in flight, on a GPU (docs/performance.md)."""


LONE_MAX = 4
"""The most spheres a scene of more primitives than FLAT_MAX may have for its rays to test them
before the walk, outside the BVH (app/compiler/compiled.py), rather than in its leaves: a tree of
triangles alone walks without the sphere leaves' branch and code (docs/notes/performance-2026-11.md,
2026-11-27: lone spheres). Each such sphere costs every ray one test, as a box of a 4-wide node
does."""
