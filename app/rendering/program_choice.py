"""Which kernels render (the scene's own program, the generic one, or BDPT's) and the switch
from one to another: a part of the Renderer (app/rendering/renderer.py), which is one."""

from dataclasses import replace

import numpy as np
import pyopencl as cl

from pathtrace.compiler.builder import await_kernels_ahead
from pathtrace.compiler.compiled import SCENE_BUFFERS
from pathtrace.device.features import Features
from pathtrace.device.opencl import keeps_own_cache
from pathtrace.device.programs import in_build_thread
from pathtrace.device.types import RENDER_PARAMS
from pathtrace.errors import UserError
from pathtrace.rendering import bdpt


class ProgramChoice:
    """The Renderer's choice of program (self.program and its kernels)."""

    def _select_program(self):
        """The kernels for the scene: its own, specialised to its shapes, materials and settings
        (pathtrace.device.features.Features), or the backend's generic program, by the backend's mode
        (pathtrace.device.programs). With "auto", the scene's own program, tuned, is built in the
        background, and add_samples switches to it once it is there, the average going on;
        until then the generic program renders, or where that is not built (NVIDIA's driver
        takes minutes over it: `pathtrace devices --check` builds it, and marks it unused where a
        driver builds it wrongly) the scene's own program untuned, one build. The background build starts once the first pass is queued, so that
        it takes no core from the first image, and a render of one pass builds nothing more
        (switch_when_built)."""
        features = self._features(self.settings.integrator)
        program, generic, awaited = self._choice(features)
        self._awaited, self._build_due = awaited, False
        self._use_program(program if program is not None else self.backend.program_for(features, tuned=awaited is None),
                          generic)

    def _choice(self, features: Features) -> tuple:
        """(the program that renders now, or None where it is the scene's own, to be built:
        untuned where the third is not None; whether it is the generic one; the features of the
        program to switch to once its tuned build is there, or None)."""
        mode = self.backend.mode
        # the generic program has no bidirectional code (a path tracer's scene compiles none),
        # nor does it count rays
        if self.settings.integrator != "path" or mode == "specialised" or self.traversal_stats \
                or self.divergence_stats:
            return None, False, None
        if mode == "generic":
            return self.backend.generic(features.media), True, None
        own = self.backend.programs.built(features)
        if own is not None:
            return own, False, None
        generic = self.backend.built_generic(features.media)
        return generic, generic is not None, features

    def start_program(self):
        """Starts, in the background, the build of the scene's own program where _select_program
        would wait for it: a path tracer's program needs nothing of the scene's tree
        (CompiledScene.features), so Renderer.set_scene starts it before building the tree. BDPT's
        checks the light table, which the tree orders."""
        if self.settings.integrator != "path" or self.backend.mode == "generic":
            return       # the generic mode's program: built at open, or built by _select_program
        features = self._features("path")
        program, _, awaited = self._choice(features)
        if program is None:
            self.backend.programs.start(features, tuned=awaited is None, after=self._tree_kernels_first())

    def _tree_kernels_first(self):
        """What a program's build in the background waits for first: on PoCL, which compiles one
        thing at a time in a process, where the scene's tree is still to be built, the tree's
        build kernels compiled ahead (await_kernels_ahead), which the first image needs first;
        elsewhere nothing (None)."""
        queue = self.backend.queue
        if keeps_own_cache(queue.device) and self.compiled.tree_ended is None:
            return lambda: await_kernels_ahead(queue)
        return None

    def _features(self, integrator: str) -> Features:
        """What the scene's own program needs to render with these settings and `integrator`:
        for BDPT and light tracing (a UserError, one line, for what they cannot render), their
        depth, and no light tree, since they choose lights by power (_light_sampler)."""
        features = replace(self.compiled.features(self.settings, self.camera),
                           traversal_stats=self.traversal_stats, divergence_stats=self.divergence_stats,
                           path_queue=self.queue_plan()[0], path_sort=self.sorts_queue(),
                           kernels="all" if self.all_kernels else "render_nee" if self.settings.nee else "render")
        if integrator == "path":
            return features
        bdpt.check(self.scene.source or self.scene.name, features, integrator, self.compiled.lights)
        return replace(features, light_tree=False, bdpt=bdpt.depth(self.settings.max_depth, integrator),
                       light_tracing=integrator == "ptracer",
                       photons=self.uses_photons(integrator), kernels=features.kernels if self.all_kernels else "bdpt")

    def _aux_features(self) -> Features:
        """The features of the scene's own auxiliary program (render_aovs and pick: Features.kernels
        "aux"), which a pass's launches do not need: the integrator's, without what only its
        render kernels use (the queue, the counters, BDPT, the Russian roulette rule)."""
        return replace(self._features(self.settings.integrator), kernels="aux", path_queue=0, path_sort=False,
                       traversal_stats=0, divergence_stats=0, bdpt=0, light_tracing=False, photons=False,
                       russian_roulette="throughput")

    def aux_kernel(self, name: str, start_only: bool = False):
        """The kernel `name` of the auxiliary ones (render_aovs, pick) for this scene: from the
        program rendering where it holds them (a generic one, the viewer's), else from the
        scene's own auxiliary program, else, outside the specialised mode, from a generic program
        that is built; else that own program's, built now, untuned (no launch of them is long).
        With `start_only`, None, that build started in the background where it is due (set_aovs)."""
        if name in self._kernel_names:
            return None if start_only else cl.Kernel(self.program, name)
        features = self._aux_features()
        program = self.backend.programs.built(features, tuned=False)
        if program is None and self.backend.mode != "specialised":
            program = self.backend.built_generic(features.media)
        if program is None and start_only:
            self.backend.programs.start(features, tuned=False, after=self._tree_kernels_first())
            return None
        return cl.Kernel(program if program is not None else self.backend.programs.get(features, tuned=False), name)

    def integrator_ready(self, integrator: str) -> bool:
        """Whether set_settings(integrator=...) would switch without waiting for a build: the
        kernels it needs are built, else their build is started in the background (the viewer
        switches once they are). A UserError, one line, where `integrator` cannot render the
        scene."""
        features = self._features(integrator)
        if integrator == "path":
            return True
        if self.backend.programs.failed(features):
            raise UserError(f"{self.scene.name}: the {integrator} kernels did not build")
        return self.backend.ready_program(features) is not None

    def _use_program(self, program: cl.Program, generic: bool):
        if program is self.program:
            return
        self.program = program
        self._aov_kernel = None                 # (Renderer.add_samples: aux_kernel's for this program)
        self.uses_generic_program = generic     # (pathtrace.device.programs)
        self._kernel_names = set(program.kernel_names.split(";"))
        # a scene's own program holds the render kernel of its estimator (Features.kernels)
        self.kernels = {nee: cl.Kernel(program, name) for nee, name in ((False, "render"), (True, "render_nee"))
                        if name in self._kernel_names}
        # the queue's kernels are in a scene's program built with a queue depth, never in the
        # generic program, which renders without the queue until the scene's own is built
        queue = self.queue_plan()[0] and not generic
        self.continue_kernels = {nee: cl.Kernel(program, name) for nee, name in
                                 ((False, "continue_paths"), (True, "continue_paths_nee"))
                                 if name in self._kernel_names} if queue else None
        self.add_queued = cl.Kernel(program, "add_queued_paths") if queue else None
        sort = queue and self.sorts_queue()
        self.sort_kernels = (cl.Kernel(program, "sort_offsets"), cl.Kernel(program, "sort_paths")) if sort else None
        bidirectional = self.settings.integrator != "path"
        self.bdpt_kernels = (cl.Kernel(program, "render_bdpt"), cl.Kernel(program, "add_splats")) if bidirectional else None
        self.photon_kernel = cl.Kernel(program, "trace_photons") if self.uses_photons() else None

    def compile_ahead(self):
        """What starts the compile of the kernel that the first pass launches, ahead of it, on a
        device that compiles a kernel at its first launch for each work-group size (PoCL), for
        the path tracer without the queue or counts (the plan CPUs render with); else None.
        Renderer.set_scene gives it to build_tree, which calls it once the tree's BVH is built:
        PoCL compiles one kernel at a time in a process, and the builder's kernels are compiled
        then, so the render kernel compiles beside the host's work that follows (the tree's
        tables, the uploads) rather than after it, at the launch, which waits for that compile
        rather than make another (docs/notes/performance-2026-12.md, twentieth session)."""
        if not keeps_own_cache(self.backend.device.device) or self.settings.integrator != "path" \
                or self.queue_plan()[0] or self.traversal_stats or self.divergence_stats:
            return None
        features, nee = self._features("path"), self.settings.nee
        return lambda: in_build_thread(lambda: self.launch_ahead(features, nee))

    def launch_ahead(self, features: Features, nee: bool):
        """A launch of one work-group of the path tracer's kernel of the program that renders
        `features` (the generic one or the scene's own, waiting for its build), which does
        nothing (its image has no width) but have the driver compile the kernel for the render
        launches' work-group size; on its own queue, so that it waits for no launch of the tree's."""
        program, _, awaited = self._choice(features)
        if program is None:
            program = self.backend.program_for(features, tuned=awaited is None)
        kernel = cl.Kernel(program, "render_nee" if nee else "render")
        context = self.backend.context
        # kernels/integrator.cl, RENDER_KERNEL: the scene's buffers, the parameters, the sums, the
        # queue and its counters, the queue's capacity, the results: buffers but two
        args = [cl.Buffer(context, cl.mem_flags.READ_WRITE, 64)] * kernel.num_args
        args[len(SCENE_BUFFERS)] = np.zeros((), RENDER_PARAMS)
        args[-2] = np.int32(0)
        kernel.set_args(*args)
        _, group = self.launch_grid(1)
        cl.enqueue_nd_range_kernel(cl.CommandQueue(context, self.backend.device.device), kernel, group, group).wait()

    def switch_when_built(self, wait: bool = False) -> bool:
        """Switches to the scene's own tuned program if it is built (with `wait`, once it is);
        the average goes on. Its build starts at the first call after a whole pass is queued.
        Whether the scene's own program renders now."""
        if self._awaited is not None and (wait or self._build_due):
            program = self.backend.program_for(self._awaited) if wait else self.backend.ready_program(self._awaited)
            if program is not None:
                self._awaited = None
                self._use_program(program, generic=False)
            elif self.backend.programs.failed(self._awaited):    # said once, by the backend
                self._awaited = None
        return not self.uses_generic_program

    def describe_programs(self) -> str:
        """Which program drew the samples since the last reset, in words, where the generic
        program drew any (else "")."""
        if not self.generic_samples:
            return ""
        if self.generic_samples == self.samples:
            return (f"{self.samples} spp from the generic kernels"
                    + (" (the scene's own were still building)"
                       if self._awaited is not None and self.backend.programs.under_way(self._awaited) else ""))
        return f"the first {self.generic_samples} of {self.samples} spp from the generic kernels, the rest from the scene's own"

    @property
    def building_program(self) -> bool:
        """Whether the scene's own program is being built, to switch to (switch_when_built)."""
        return self._awaited is not None
