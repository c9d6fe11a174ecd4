"""The BVH builder of each OpenCL device (pathtrace.compiler.bvh builds the tree on it): the build
kernels (kernels/build/), made once per device, and when they compile ahead of the tree that needs
them. PoCL compiles a kernel at its first launch, one at a time in a process; a new scene's tree
waits for its ten kernels unless they compiled beside the scene's reading. A scene compiled
before its devices open says what its tree needs (expect_tree, no_device_tree); its reader says
earlier that it is likely to need one (pathtrace.scene.meshes: large_scene_named); a devices'
opening makes its builders accordingly (api.DevicesOpening)."""

import re
import threading

import numpy as np
import pyopencl as cl

from pathtrace.scene.meshes import large_scene_named

# these three reach kernels/build/collapse.cl as build options
MAX_LEAF_SIZE = 4
MAX_DEPTH = 30              # of the binary tree: kernels/bvh.cl's stack holds 48 = 3 x 30 / 2 + 3
TRAVERSAL_COST = 0.5        # relative to one primitive test, as in pbrt-v4's BVH build
GROUP = 256                 # SCAN_GROUP of kernels/build/ploc.cl; every build kernel uses it
# PoCL compiles a kernel at its first launch for grids of at least 65,536 work-items per dimension,
# a compile that serves smaller grids too; a smaller first launch compiles a `smallgrid` variant
# that serves only those, and a larger launch after it compiles the kernel again
WHOLE_GRID = 65536


class Builder:
    """The build kernels (kernels/build/) on one OpenCL device."""

    def __init__(self, queue: cl.CommandQueue):
        from pathtrace.device.opencl import build_cached
        from pathtrace.resources import resource_dir

        self.queue = queue
        folder = resource_dir("kernels")
        source = "\n".join(f'#line 1 "{name}"\n' + (folder / name).read_text() for name in
                           ("types.h", "build/morton.cl", "build/ploc.cl", "build/collapse.cl"))
        options = [f"-DMAX_LEAF_SIZE={MAX_LEAF_SIZE}", f"-DMAX_DEPTH={MAX_DEPTH}",
                   f"-DTRAVERSAL_COST={TRAVERSAL_COST}f"]
        # untuned: its short, memory-bound launches gain nothing from register caps, whose
        # trials doubled its build on an H200 (0.84-0.88 s against 0.41-0.44 s), on a cold
        # start's path to a new scene's tree (docs/notes/performance-2026-11.md, sixteenth session)
        self.program = build_cached(queue.context, queue.device, source, options, tune=False).program
        self.kernels = {k.function_name: k for k in self.program.all_kernels()}
        # each kernel's arguments as words ("global const int2 *child"), for launch_ahead
        self.signatures = {name: [a.split() for a in args.split(",")]
                           for name, args in re.findall(r"^kernel void (\w+)\(([^)]*)\)", source, re.M)}
        assert self.signatures.keys() == self.kernels.keys(), "kernels/build/: a kernel launch_ahead cannot read"
        self._ahead = False     # whether compile_ahead has begun
        self.ahead_done = threading.Event()     # and ended

    def compile_ahead(self):
        """On a device that compiles a kernel at its first launch (PoCL, one kernel at a time in a
        process), has every build kernel compiled now, in a build thread (launch_ahead), beside
        the host's work before the tree (reading and compiling the scene), rather than each at
        its first launch in the build, between the launches' work: a new scene of 870,400
        triangles came 0.35 s sooner on two cores (docs/notes/performance-2026-12.md, twenty-first
        session). A build's launch of a kernel whose compile is under way waits for it rather
        than compile it again. Once per builder; a failure shows at the build's own launch."""
        from pathtrace.device.opencl import keeps_own_cache
        from pathtrace.device.programs import in_build_thread

        with _ahead_lock:
            if self._ahead:
                return
            self._ahead = True
        try:
            if keeps_own_cache(self.queue.device):
                in_build_thread(self.launch_ahead, then=self.ahead_done.set)
                return
        except Exception:
            pass
        self.ahead_done.set()       # nothing compiles ahead: no one waits for it

    def launch_ahead(self):
        """Launches every build kernel once, on a queue of its own, over WHOLE_GRID work-items
        that all return at once (their counts are 0), and waits for them: the kernels are then
        compiled for the build's launches of every size."""
        context = self.queue.context
        queue = cl.CommandQueue(context, self.queue.device)
        nbytes = WHOLE_GRID // GROUP * 8        # what a kernel writes at counts of 0: mark_merges'
        zeros = cl.Buffer(context, cl.mem_flags.READ_WRITE, nbytes)     # group sums, an int2 each
        cl.enqueue_fill_buffer(queue, zeros, np.zeros(1, np.int32), 0, nbytes)
        scalars = {"int": np.int32(0), "float4": np.zeros(4, np.float32)}
        for name, args in self.signatures.items():
            kernel = cl.Kernel(self.program, name)      # not self.kernels': the build sets their arguments
            kernel.set_args(*(zeros if "global" in arg else scalars[arg[0]] for arg in args))
            cl.enqueue_nd_range_kernel(queue, kernel, (WHOLE_GRID,), (GROUP,))
        queue.finish()

    def launch(self, name: str, count: int, *args):
        """Kernel `name` over `count` items, in work-groups of GROUP (the kernels skip the rest)."""
        groups = max(-(-count // GROUP), 1)
        self.kernels[name](self.queue, (groups * GROUP,), (GROUP,), *args)
        return groups

    def buffer(self, nbytes: int) -> cl.Buffer:
        return cl.Buffer(self.queue.context, cl.mem_flags.READ_WRITE, max(int(nbytes), 4))

    def filled(self, value, count: int) -> cl.Buffer:
        buf = self.buffer(count * value.itemsize)
        cl.enqueue_fill_buffer(self.queue, buf, value, 0, count * value.itemsize)
        return buf

    def read(self, buf: cl.Buffer, count: int, dtype, offset: int = 0) -> np.ndarray:
        out = np.empty(count, dtype)
        if count:
            cl.enqueue_copy(self.queue, out, buf, src_offset=offset * np.dtype(dtype).itemsize, is_blocking=True)
        return out

    def write(self, buf: cl.Buffer, array: np.ndarray, offset: int = 0):
        array = np.ascontiguousarray(array)
        if array.size:
            cl.enqueue_copy(self.queue, buf, array, dst_offset=offset * array[0].nbytes, is_blocking=True)


_builders: dict = {}
_builders_lock = threading.Lock()    # a command's devices open (api.DevicesOpening) beside its first build
_ahead_lock = threading.Lock()
_tree_expected = False      # expect_tree's flag, until a tree is built
_tree_without_device = False    # no_device_tree's flag, until a tree is expected


def building() -> bool:
    """Whether a builder's kernels are being built (app/cli/console.py leaves past the
    interpreter's teardown then, as around a scene's program's build)."""
    return _builders_lock.locked()


def builder_for(queue: cl.CommandQueue = None, ahead: bool = False) -> Builder:
    """The builder on `queue`'s device, or, without one, on the first device (GPUs first) whose
    platform builds it; made once per queue, by the first thread to ask. Its kernels compile
    ahead (Builder.compile_ahead) where a tree is expected, or where `ahead`."""
    with _builders_lock:
        if queue not in _builders:
            _builders[queue] = Builder(queue) if queue is not None else _first_working_builder()
        builder = _builders[queue]
    if _tree_expected or ahead:
        builder.compile_ahead()
    return builder


def expect_tree():
    """Says that a tree the BVH cache lacks is about to be built (compile_before_devices): the
    builders made now or later compile their kernels ahead (Builder.compile_ahead). The flag is
    set before the builders are listed, and builder_for reads it after adding one, so that no
    builder misses it."""
    global _tree_expected, _tree_without_device
    _tree_expected, _tree_without_device = True, False
    for builder in list(_builders.values()):
        builder.compile_ahead()


def no_device_tree():
    """Says that the scene's tree was had without a device (the host built it, or the BVH cache
    held it; compile_before_devices): devices whose opening ends after this make no builder in
    advance (builder_wanted), whose build an H200 made beside the scene's own program's on a cold
    start, for nothing (docs/notes/performance-2026-12.md, twenty-third session)."""
    global _tree_without_device
    _tree_without_device = True


def tree_unknown():
    """Forgets what the last scene's tree needed: a new opening of devices (api.DevicesOpening),
    begun before its scene is compiled, makes builders unless that scene's tree needs none."""
    global _tree_without_device
    _tree_without_device = False
    large_scene_named.clear()


def tree_likely() -> bool:
    """Whether the scene is likely to need a tree built on a device, before its compile knows
    (expect_tree): its reader has named large mesh files (pathtrace.scene.meshes). A devices'
    opening then has the builder's kernels compiled ahead beside the reading, which a new scene
    of 870,400 triangles in 850 OBJ files spent 1.2 s on with one of two cores idle
    (docs/notes/performance-2026-12.md, twenty-fifth session); a scene read from the scene
    cache names none, and a small one's tree is built on the host."""
    return _tree_expected or large_scene_named.is_set()


def builder_wanted() -> bool:
    """Whether opening devices should make their builders in advance (api.DevicesOpening): unless
    the scene's tree is known by then to need none (no_device_tree). A builder not made in
    advance is made by the first tree that needs it (a larger scene opened later in the viewer:
    on its critical path, 0.4 s where NVIDIA's build is cold)."""
    return not _tree_without_device


def tree_built():
    """The expected tree is built (build_bvh): what is made later compiles nothing ahead, and a
    program's build waits for nothing (await_kernels_ahead)."""
    global _tree_expected
    _tree_expected = False


def await_kernels_ahead(queue: cl.CommandQueue):
    """Where a tree is expected (expect_tree), waits for the kernels of the builder on `queue`'s
    device to be compiled ahead, the builder made first if its device's opening has not made it:
    PoCL compiles one thing at a time in a process, and a scene's program built before them
    (0.4 s on two cores) delays the tree, which the first image needs first
    (docs/notes/performance-2026-12.md, twenty-first session)."""
    if not _tree_expected:
        return
    try:
        builder = builder_for(queue)
    except Exception:           # the tree's build says why
        return
    builder.ahead_done.wait()


def _first_working_builder() -> Builder:
    from pathtrace.device.opencl import HOW_TO_GET_ONE, list_devices, no_device
    from pathtrace.errors import UserError

    devices = list_devices()
    if not devices:
        raise UserError(no_device())
    for d in sorted(devices, key=lambda d: d.kind != "GPU"):
        try:
            return Builder(cl.CommandQueue(cl.Context([d.device])))
        except cl.Error:
            continue
    raise UserError(f"no OpenCL device can build the BVH: {HOW_TO_GET_ONE}")
