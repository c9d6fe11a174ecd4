"""Shared fixtures: one OpenCL device (PoCL on the CPU in CI) and test kernels built beside the
real ones."""

import os
import tempfile
from pathlib import Path

import numpy as np
import pyopencl as cl
import pytest

from pathtrace.compiler.compiled import SCENE_BUFFERS
from pathtrace.device.opencl import build_cached, build_program, choose_device
from pathtrace.device.features import Features

ROOT = Path(__file__).resolve().parent.parent

# The BVH cache (pathtrace.compiler.bvh_cache) is off in the tests, theirs and their commands': every
# scene is built, and nothing is written to the user's cache; tests/test_bvh_cache.py turns it on.
os.environ.setdefault("PATHTRACE_BVH_CACHE", "0")
# Nor are scenes read from its cache of scenes (pathtrace.scene.read_cache): tests/test_read_cache.py.
os.environ.setdefault("PATHTRACE_SCENE_CACHE", "0")
# Nor to its cache of kernel binaries and path-queue verdicts (Renderer.choose_queue_plan), whose
# verdicts would spare a later run the trials that tests count.
os.environ.setdefault("PATHTRACE_CACHE", tempfile.mkdtemp(prefix="pathtrace-tests-"))
# Renders draw from the generic programs alone (pathtrace.device.programs: with media and
# without), two builds shared by every test, where each scene's own program would be a build of its own (about 220 of them, most of
# the suite's time on two cores). Tests marked `specialised` render with the scenes' own
# programs: those about what those programs compile, trace and cache, and the references, which
# check what a render converges with; tests/test_programs.py compares the two on every test scene.
os.environ.setdefault("PATHTRACE_PROGRAM", "generic")


def pytest_configure(config):
    config.addinivalue_line("markers", "specialised: renders with each scene's own program (PATHTRACE_PROGRAM "
                                       "specialised), for tests about what the specialised programs compile")


@pytest.fixture(autouse=True)
def program_mode(request, monkeypatch):
    """In a test marked `specialised`: the scenes' own programs, for the test's backend, the
    devices the API keeps open and the commands it runs."""
    if request.node.get_closest_marker("specialised") is None:
        return
    from pathtrace import api
    # the session's backend is opened (if this is its first test) before the mode changes, so
    # that it keeps the generic mode, which the undo below restores, for the tests after this one
    backend = request.getfixturevalue("backend")
    monkeypatch.setenv("PATHTRACE_PROGRAM", "specialised")
    monkeypatch.setattr(api, "_backends", dict(api._backends))    # those it opens go with it
    for backend in [backend, *(b for group in api._backends.values() for b in group)]:
        monkeypatch.setattr(backend, "mode", "specialised")


@pytest.fixture(autouse=True)
def no_tree_expected(monkeypatch):
    """Each test starts without an earlier one's expectation of a tree (pathtrace.compiler.builder:
    expect_tree), under which the builders it makes would compile their kernels ahead, or its
    word that a tree needed no device (no_device_tree), under which devices open without them,
    or its reader's word that a scene was large (tree_likely)."""
    from pathtrace.compiler import builder
    monkeypatch.setattr(builder, "_tree_expected", False)
    monkeypatch.setattr(builder, "_tree_without_device", False)
    builder.large_scene_named.clear()


@pytest.fixture(scope="session")
def backend():
    """The device the tests run on: PATHTRACE_TEST_DEVICE, else the first CPU."""
    return choose_device(os.environ.get("PATHTRACE_TEST_DEVICE", "cpu"))


class KernelRunner:
    """Builds the kernels plus a test kernel (the program of `features`: by default every shape
    and material, no textures), or with `options` the source alone, and runs it on NumPy arrays."""

    def __init__(self, backend, source, features=Features(), options=None):
        device = backend.device.device
        self.ctx = cl.Context([device])
        self.queue = cl.CommandQueue(self.ctx)
        built = (build_program(self.ctx, device, source, features=features) if options is None
                 else build_cached(self.ctx, device, source, options))
        self.program = built.program

    def __call__(self, name, global_size, *args):
        """Runs kernel `name` over global_size work-items, in work-groups of one: PoCL compiles a
        kernel again for each work-group size, and where none is given picks one from the global
        size, which the tests vary (bsdf_eval ran at 16 sizes in a run of the suite, an all-BSDF
        kernel compiled for each new divisor); one size is one compile, 7 % of these tests' CPU."""
        bufs, outs = [], []
        for a in args:
            if isinstance(a, np.ndarray) and a.ndim > 0:   # 0-d: a struct passed by value
                flags = cl.mem_flags.READ_WRITE | cl.mem_flags.COPY_HOST_PTR
                buf = cl.Buffer(self.ctx, flags, hostbuf=np.ascontiguousarray(a))
                bufs.append(buf)
                outs.append((buf, a))
            else:
                bufs.append(a)
        kernel = cl.Kernel(self.program, name)
        kernel(self.queue, (global_size,), (1,), *bufs)
        for buf, a in outs:
            cl.enqueue_copy(self.queue, a, buf)
        self.queue.finish()


@pytest.fixture(scope="session")
def kernels(backend):
    cache = {}

    def make(source, features=Features()):
        if (source, features) not in cache:
            cache[source, features] = KernelRunner(backend, source, features)
        return cache[source, features]
    return make


def layout_features(compiled) -> Features:
    """The features of the default program (which test kernels are built with) that a compiled
    scene's layout needs: its few spheres outside the tree (LONE_SPHERES), which a kernel built
    without would never meet, and, where it has analytic shapes, every kind of them: one program
    for the scenes of each kind, as the generic program dispatches them (a build saved per kind;
    the scenes' own programs, with their kinds alone, are tests/test_shapes.py's renders)."""
    from pathtrace.shapes import SHAPES
    return Features(lone_spheres=compiled.lone_spheres, shapes=tuple(SHAPES) if compiled.shape_kinds else ())


def scene_arrays(compiled):
    """The arrays of a CompiledScene in the order of the kernels' SCENE_KERNEL_ARGS (empty ones
    padded to one element, as the Renderer uploads them)."""
    marginal, conditional = compiled.scene.environment.sampling_cdfs()
    arrays = {**compiled.geometry_arrays(), **compiled.material_arrays(), "env": compiled.scene.environment.rgba(),
              "env_marginal": marginal, "env_conditional": conditional}
    return [np.ascontiguousarray(a) if a.size else np.zeros(1, a.dtype)
            for a in (arrays[name] for name in SCENE_BUFFERS)]


# The longest test files, longest first (their shares of the suite's time on two cores,
# 2026-11-29: the references 12 %, the next nine 4-7 % each). The workers take whole files
# (--dist loadfile), so a long one begun last leaves the other worker idle at the end.
LONGEST_FILES = ("test_reference.py", "test_nee.py", "test_programs.py", "test_bench.py", "test_path_queue.py",
                 "test_bdpt.py", "test_shapes.py", "test_cli.py", "test_viewer.py", "test_bvh.py", "test_pbrt.py")


def pytest_collection_modifyitems(items):
    rank = {name: k for k, name in enumerate(LONGEST_FILES)}
    items.sort(key=lambda item: rank.get(item.path.name, len(LONGEST_FILES)))
