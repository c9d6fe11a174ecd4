"""The generic program and the switch to a scene's own (app/device/programs.py): the generic program
renders every test scene as the scene's own program does, within noise, whatever the camera,
filter, Russian roulette rule and scene layout it reads at run time; a renderer switches to the
scene's program mid-accumulation once it is built, the average going on; a build that fails
leaves the generic program rendering, said in one line."""

import threading
from pathlib import Path

import numpy as np
import pytest

import pathtrace.compiler.builder as builder_module
from pathtrace.device.opencl import Backend
from pathtrace.device.features import Features
from pathtrace.filters import PixelFilter
from pathtrace.device.programs import Programs
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
from pathtrace.scene.toml_reader import read_scene_dict
from tests.stats import z_test

SCENES = sorted(p for p in (Path(__file__).parent / "scenes").iterdir() if p.suffix in (".xml", ".pbrt"))
SIZE = 16
SPP = 128


def with_mode(backend: Backend, mode: str) -> Backend:
    return backend.with_mode(mode)


def building_with(backend: Backend, build, tunes: bool = False, generic: bool = True) -> Backend:
    """An "auto" backend on the same device whose scenes' programs `build` builds, with the
    generic program already built where `generic`."""
    auto = with_mode(backend, "auto")
    auto.programs = Programs(build, auto.device.name, tunes)
    if generic:
        for media in (False, True):
            auto.programs.add(Features.generic_program(media), True, backend.generic(media))
    return auto


def render(backend, scene, spp=SPP):
    r = Renderer(backend, scene, SIZE, SIZE)
    for _ in range(spp // 64):
        r.add_samples(64)
    r.finish()
    return r


def same_image(a: Renderer, b: Renderer):
    ok, p, threshold = z_test(a.mean(), a.variance() / a.samples, b.mean(), b.variance() / b.samples, block=4)
    assert ok, f"smallest p-value {p:.3g} below the Sidak threshold {threshold:.3g}"


@pytest.fixture(scope="module")
def generic(backend):
    return with_mode(backend, "generic")


@pytest.fixture(scope="module")
def specialised(backend):
    return with_mode(backend, "specialised")


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.name)
def test_the_generic_program_renders_each_test_scene_as_its_own_program(generic, specialised, path):
    # with the settings of tests/test_reference.py, whose scenes' own programs (a Russian
    # roulette rule is compiled in: RUSSIAN_ROULETTE) these then are, built once for both
    scene = load_scene(str(path)).with_settings(max_depth=8, russian_roulette="off")
    a, b = render(generic, scene), render(specialised, scene)
    assert a.uses_generic_program and not b.uses_generic_program
    same_image(a, b)


def test_scenes_without_media_render_with_the_generic_program_without_them(generic):
    """Two generic programs (Features.generic_program): a scene with neither media nor null
    surfaces draws from the one that compiles no volumetric code."""
    plain = Renderer(generic, load_scene("cornell-box"), SIZE, SIZE)
    fog = Renderer(generic, load_scene(str(Path(__file__).parent / "scenes" / "media-fog.xml")), SIZE, SIZE)
    assert plain.uses_generic_program and fog.uses_generic_program
    assert plain.program is generic.generic(media=False) and fog.program is generic.generic(media=True)
    assert plain.program is not fog.program
    assert "MEDIA" not in Features.generic_program(media=False).defines()


@pytest.mark.parametrize("name,settings", [
    ("teapot-sky", {}),                                           # lone spheres beside the triangles' tree
    ("simple-diffuse", {}),                                       # five spheres, tested all (flat)
    ("cornell-box", {"russian_roulette": "albedo"}),
    ("cornell-box", {"russian_roulette": "off", "max_depth": 6}),
    ("cornell-box", {"filter": PixelFilter("gaussian")}),
    ("cornell-box", {"filter": PixelFilter("tent")}),
    ("cornell-box", {"light_sampler": "tree"}),
], ids=lambda v: v if isinstance(v, str) else "-".join(f"{k}={getattr(x, 'name', x)}" for k, x in v.items()))
def test_the_generic_program_reads_its_choices_at_run_time(generic, specialised, name, settings):
    scene = load_scene(name)
    scene = scene.with_settings(**settings) if settings else scene
    a, b = render(generic, scene), render(specialised, scene)
    assert a.params(1)["layout"] == b.params(1)["layout"]
    assert bool(a.params(1)["layout"] & 16) == bool(a.compiled.flat)      # LAYOUT_FLAT
    same_image(a, b)


def test_the_generic_program_walks_a_two_level_bvh(generic, specialised, monkeypatch):
    from pathtrace.scene import instances
    monkeypatch.setattr(instances, "FLATTEN_MAX", -1)       # instances.xml's copies are few
    scene = load_scene(str(Path(__file__).parent / "scenes" / "instances.xml"))
    a, b = render(generic, scene), render(specialised, scene)
    assert a.compiled.two_level and a.params(1)["layout"] & 2      # LAYOUT_INSTANCES
    same_image(a, b)


def test_an_orthographic_camera_through_the_generic_program(generic, specialised):
    scene = load_scene("cornell-box")
    camera = scene.camera.as_type("orthographic", height=1.2)
    a, b = Renderer(generic, scene, SIZE, SIZE), Renderer(specialised, scene, SIZE, SIZE)
    for r in (a, b):
        r.set_camera(camera)
        for _ in range(SPP // 64):
            r.add_samples(64)
        r.finish()
    same_image(a, b)


class GatedBuild:
    """A backend's build of scenes' programs that waits until the test opens the gate."""

    def __init__(self, backend, fail=False):
        self.backend, self.fail = backend, fail
        self.gate = threading.Event()
        self.started = threading.Event()
        self.finished = threading.Event()

    def __call__(self, features, tune):
        self.started.set()
        self.gate.wait(60)
        try:
            if self.fail:
                raise RuntimeError("clBuildProgram failed: BUILD_PROGRAM_FAILURE\nerror: an injected failure")
            return self.backend.program_for(features, tune)
        finally:
            self.finished.set()


def test_a_renderer_switches_to_the_scenes_program_mid_accumulation(backend, specialised):
    gated = GatedBuild(specialised)
    auto = building_with(backend, gated)
    scene = load_scene("cornell-box")
    r = Renderer(auto, scene, SIZE, SIZE)
    resets = r.resets
    r.add_samples(64)
    r.finish()
    assert not gated.started.is_set()       # nothing builds behind the first image
    r.add_samples(64)                       # the next pass starts the scene's own build
    r.finish()
    assert gated.started.wait(60) and r.uses_generic_program and r.samples == 128   # still under way
    assert r.describe_programs() == "128 spp from the generic kernels (the scene's own were still building)"
    gated.gate.set()
    assert r.switch_when_built(wait=True)
    for _ in range(SPP // 64 - 2):
        r.add_samples(64)
    r.finish()
    assert not r.uses_generic_program and r.samples == SPP and r.resets == resets   # the average went on
    same_image(r, render(specialised, scene))


def test_a_failed_build_leaves_the_generic_program_rendering(backend, capsys):
    gated = GatedBuild(backend, fail=True)
    auto = building_with(backend, gated)
    r = Renderer(auto, load_scene("cornell-box"), SIZE, SIZE)
    assert r.building_program
    r.add_samples(1)
    r.add_samples(1)         # starts the build, after the first pass
    gated.gate.set()
    assert gated.finished.wait(60)
    for _ in range(1000):
        r.add_samples(1)       # each asks whether the build is done
        if not r.building_program:
            break
    r.finish()
    assert r.uses_generic_program and not r.building_program and r.samples <= 1000
    assert np.isfinite(r.mean()).all() and r.mean().max() > 0
    lines = [line for line in capsys.readouterr().err.splitlines() if "did not build" in line]
    assert len(lines) == 1 and "an injected failure" not in lines[0] and "BUILD_PROGRAM_FAILURE" in lines[0]


def test_path_queue_plans_render_with_the_generic_program_until_theirs_is_built(backend, specialised):
    """The generic program has no continuation queue: launches go without it meanwhile."""
    gated = GatedBuild(specialised)
    auto = building_with(backend, gated)
    scene = load_scene("cornell-box").with_settings(path_queue=2)
    r = Renderer(auto, scene, SIZE, SIZE)
    r.add_samples(64)
    r.finish()
    assert r.uses_generic_program and r.continue_kernels is None
    gated.gate.set()
    r.switch_when_built(wait=True)
    assert r.continue_kernels is not None
    for _ in range(SPP // 64 - 1):
        r.add_samples(64)
    r.finish()
    same_image(r, render(specialised, scene))


def test_without_the_generic_program_the_first_image_waits_for_one_untuned_build(backend, specialised):
    """Where the generic program is not built (NVIDIA's driver takes minutes over it, which
    `pathtrace devices --check` spends once): the scene's own program is built once, untuned, for
    the first image, nothing else building beside it, and the tuned one (app/device/occupancy.py),
    built after it in the background, replaces it once built."""
    tuned = threading.Event()
    built = []

    def build(features, tune):
        assert not features.generic
        built.append(tune)
        if tune:
            assert tuned.wait(60)
        return specialised.program_for(features)
    auto = building_with(backend, build, tunes=True, generic=False)
    scene = load_scene("cornell-box")
    r = Renderer(auto, scene, SIZE, SIZE)
    assert not r.uses_generic_program and r.building_program and built[0] is False
    r.add_samples(64)
    r.finish()
    tuned.set()
    assert r.switch_when_built(wait=True) and not r.building_program and built == [False, True]
    for _ in range(SPP // 64 - 1):
        r.add_samples(64)
    r.finish()
    assert r.samples == SPP and r.generic_samples == 0
    same_image(r, render(specialised, scene))



def kernels_of(r: Renderer) -> set:
    return set(r.program.kernel_names.split(";"))


def test_a_scenes_own_program_holds_the_kernels_its_passes_launch_and_no_others(specialised):
    r = Renderer(specialised, load_scene("cornell-box"), SIZE, SIZE)
    assert kernels_of(r) == {"render_nee"}
    r.set_settings(nee=False)
    assert kernels_of(r) == {"render"}
    r.add_samples(16)
    r.finish()
    assert r.mean().max() > 0 and np.isfinite(r.mean()).all()
    r.set_settings(integrator="bdpt")
    assert {"render", "render_nee", "render_aovs", "pick"}.isdisjoint(kernels_of(r)) and "render_bdpt" in kernels_of(r)


def test_the_viewers_programs_hold_every_kernel(specialised):
    """A user may turn NEE, the denoiser or picking on at any moment: none waits for a build."""
    r = Renderer(specialised, load_scene("cornell-box"), SIZE, SIZE, all_kernels=True)
    every = {"render", "render_nee", "render_aovs", "pick"}
    assert every <= kernels_of(r)
    r.set_settings(integrator="bdpt")
    assert every | {"render_bdpt"} <= kernels_of(r)


class AuxGated(GatedBuild):
    """Builds scenes' render programs at once and their auxiliary programs once the gate opens."""

    def __call__(self, features, tune):
        return super().__call__(features, tune) if features.kernels == "aux" else \
            self.backend.program_for(features, tune)


def test_the_aovs_come_from_a_program_of_their_own_built_beside_the_scenes(backend, specialised):
    gated = AuxGated(specialised)
    scene = load_scene("cornell-box")
    r = Renderer(building_with(backend, gated, generic=False), scene, SIZE, SIZE)
    r.set_aovs(True)
    assert gated.started.wait(60)           # its build starts with the AOVs, before any pass
    gated.gate.set()
    ref = Renderer(specialised, scene, SIZE, SIZE, all_kernels=True)
    ref.set_aovs(True)
    for renderer in (r, ref):
        for _ in range(5):
            renderer.add_samples(4)
        renderer.finish()
    assert "render_aovs" not in kernels_of(r)
    aovs, expected = r.read_aovs(), ref.read_aovs()
    assert r.read_albedo_sum()[..., 3].max() == 16           # over the first 16 samples
    for name, image in expected.items():
        assert image.max() > 0 and np.allclose(aovs[name], image, rtol=1e-5, atol=1e-6), name


def test_aovs_asked_with_the_scene_build_their_program_beside_its_tree(backend, specialised, monkeypatch):
    """A render that asks for the AOVs from the start (api.prepare's aovs) has their program's
    build started with the scene's own, before the tree, not after it."""
    from pathtrace.compiler.compiled import CompiledScene
    gated = AuxGated(specialised)
    build_tree = CompiledScene.build_tree
    order = []

    def tree_after(compiled, queue=None, cached_only=False, when_bvh_built=None):
        order.append(("tree", gated.started.is_set()))
        return build_tree(compiled, queue, cached_only, when_bvh_built)
    monkeypatch.setattr(CompiledScene, "build_tree", tree_after)
    r = Renderer(building_with(backend, gated, generic=False), load_scene("cornell-box"), SIZE, SIZE, aovs=True)
    gated.gate.set()
    r.add_samples(4)
    r.finish()
    assert ("tree", True) in order and r.read_aovs()["albedo"].max() > 0


def test_the_generic_program_draws_the_aovs_and_picks_while_the_scenes_own_builds_nothing_for_them(backend):
    gated = AuxGated(backend)
    r = Renderer(building_with(backend, gated), load_scene("cornell-box"), SIZE, SIZE)
    r.set_aovs(True)
    r.add_samples(4)
    r.finish()
    assert r.uses_generic_program and r.read_aovs()["albedo"].max() > 0
    assert r.pick(r.camera.eye, r.camera.frame()[0]) is not None and not gated.started.is_set()


def test_aovs_turned_off_between_a_passs_bands_are_not_drawn(specialised):
    r = Renderer(specialised, load_scene("cornell-box"), SIZE, SIZE)
    r.set_aovs(True)
    r.add_samples(1, rows=(0, SIZE // 2))
    r.set_aovs(False)
    r.add_samples(1, rows=(SIZE // 2, SIZE))
    r.finish()
    assert r.samples == 1 and np.isfinite(r.mean()).all()


def test_pick_finds_the_shape_along_a_ray_and_its_distance(specialised):
    scene = read_scene_dict({"camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
                             "materials": {"grey": {"type": "diffuse", "rho_d": 0.5}},
                             "spheres": [{"center": [0, 0, 0], "radius": 1.0, "material": "grey", "name": "ball"}]})
    r = Renderer(specialised, scene, SIZE, SIZE)
    assert "pick" not in kernels_of(r)
    shape = r.pick([0, 0, 5], [0, 0, -1])
    assert shape.kind == "sphere" and shape.name == "ball"
    assert r.hit_distance([0, 0, 5], [0, 0, -1]) == pytest.approx(4.0, rel=1e-5)
    assert r.pick([0, 0, 5], [0, 0, 1]) is None and r.hit_distance([0, 3, 5], [0, 0, -1]) is None


def open_as_render_does(backend, scene):
    from pathtrace.compiler.compiled import compile_scene
    return Renderer(backend, compile_scene(scene, backend.queue, tree=False), SIZE, SIZE)


def open_as_the_viewer_does(backend, scene):
    from pathtrace.viewer.opening import SceneOpening

    class Opening(SceneOpening):          # the viewer's part that opens scenes, its statuses kept
        def __setattr__(self, name, value):
            if name == "_status":
                statuses.append(value)
            super().__setattr__(name, value)
    opening, statuses = Opening(), []
    opening.backend = backend
    r = opening._open(*opening._compile(scene))
    r.resize(SIZE, SIZE)
    # what the window said last: that the kernels, which the tree did not wait for, are coming
    assert statuses[-1][0].startswith("preparing the kernels for cornell-box")
    return r


@pytest.mark.parametrize("open_scene", [open_as_render_does, open_as_the_viewer_does])
def test_the_scenes_program_builds_beside_its_tree(backend, specialised, monkeypatch, open_scene):
    """A scene compiled without its tree (what `render`, the Python API and the viewer do) starts
    its own program's build before the tree's: on a first start the two had run one after the
    other (the tree waits here, at most 30 s, until the build has begun)."""
    from pathtrace.compiler.compiled import CompiledScene
    asked, before_tree = threading.Event(), []
    build_tree, trees = CompiledScene.build_tree, []

    def tree_after_the_build_began(compiled, queue=None, cached_only=False, when_bvh_built=None):
        if cached_only:           # the viewer's, before the device: cornell-box is not cached
            return build_tree(compiled, queue, cached_only)
        if compiled.bvh is None:
            asked.wait(30)
        trees.append(compiled)
        return build_tree(compiled, queue, when_bvh_built=when_bvh_built)
    monkeypatch.setattr(CompiledScene, "build_tree", tree_after_the_build_began)

    def build(features, tune):
        before_tree.append(trees[-1].bvh is None if trees else True)
        asked.set()
        return specialised.program_for(features)
    auto = building_with(backend, build, generic=False)
    scene = load_scene("cornell-box")
    r = open_scene(auto, scene)
    assert before_tree == [True] and r.compiled.bvh is not None
    r.add_samples(SPP)
    r.finish()
    same_image(r, render(specialised, scene))


def lamps(extra: int):
    """TREE_MIN + extra lamps, two of them without area, and a point light: TREE_MIN - 1 + extra
    lights with a place, so that "auto" chooses them through the light tree for extra 1, not 0
    (app/lights/table.py: TREE_MIN), which the plan before the tree must foresee."""
    from pathtrace.lights import PointLight
    from pathtrace.lights.table import TREE_MIN
    from tests.test_lights import lamp_field
    scene = lamp_field(TREE_MIN + extra)
    for mesh in scene.meshes[1:3]:
        mesh.vertices[:] = mesh.vertices[0]
    scene.lights = [PointLight(np.array([0.0, 2.0, 0.0]), np.ones(3))]
    return scene


@pytest.mark.parametrize("name", [p.name for p in SCENES] + ["cornell-box", "teapot-sky", "materials", "lamps 0",
                                                             "lamps 1"])
def test_what_a_program_needs_is_known_before_the_tree(name):
    """CompiledScene.features before the tree is built (from which the program builds beside
    it) is what it is after, for every test scene, built-in scenes, and lamps at the light
    tree's threshold, two of which have no area."""
    from pathtrace.compiler.compiled import CompiledScene, compile_scene
    extra = int(name.split()[1]) if name.startswith("lamps") else None
    scene = lamps(extra) if extra is not None else load_scene(next((p for p in SCENES if p.name == name), name))
    before = CompiledScene(scene, tree=False)
    features = before.features(scene.settings, scene.camera)
    assert before.bvh is None
    after = compile_scene(scene)
    assert features == after.features(scene.settings, scene.camera)
    if extra is not None:
        assert features.light_tree == bool(extra) and features.lights == ("point",)
        assert np.count_nonzero(after.lights.prim_light >= 0) == len(scene.meshes) - 3


def test_a_tree_whose_build_failed_is_built_again_and_an_edit_builds_it(monkeypatch):
    """A scene compiled without its tree: a build of it that fails (here the BVH's, once) leaves
    it to be built again, whole; an edit's update_materials builds it where it is not built."""
    import pathtrace.compiler.compiled as compiled_module
    from pathtrace.compiler.compiled import CompiledScene, compile_scene
    scene = load_scene("cornell-box")
    cached_bvh, calls = compiled_module.cached_bvh, []

    def failing_once(*args, **kwargs):
        calls.append(None)
        if len(calls) == 1:
            raise MemoryError("the first build")
        return cached_bvh(*args, **kwargs)
    monkeypatch.setattr(compiled_module, "cached_bvh", failing_once)
    compiled = CompiledScene(scene, tree=False)
    with pytest.raises(MemoryError):
        compiled.build_tree()
    compiled.build_tree()
    whole = compile_scene(scene)
    assert len(calls) == 3 and compiled.tree_ended is not None
    arrays = {**compiled.geometry_arrays(), **compiled.material_arrays()}
    for name, array in {**whole.geometry_arrays(), **whole.material_arrays()}.items():
        assert arrays[name].tobytes() == array.tobytes(), name       # bytes: indices are NaN floats
    edited = CompiledScene(scene, tree=False)
    edited.update_materials()
    assert edited.tree_ended is not None and len(edited.material_arrays()["lights"]) == len(whole.lights.lights)


@pytest.fixture(scope="module")
def gpu_form(backend):
    """The generic program in the form GPUs build: its dispatch over BSDFs, textures and lights
    called rather than inlined (kernels/inlining.h: DISPATCH), which CPUs do not build, built
    here without CPU_DEVICE."""
    import pyopencl as cl
    from pathtrace.device.opencl import kernel_source, program_options
    generic = Features.generic_program(media=False)       # the test's scenes have no media
    options = [o for o in program_options(backend.device.device, generic) if o != "-DCPU_DEVICE"]
    program = cl.Program(backend.context, kernel_source(backend.extra, generic)).build(
        options=options, devices=[backend.device.device])
    form = with_mode(backend, "generic")
    form.programs = Programs(None, form.device.name, False)
    form.programs.add(generic, False, program)
    return form


@pytest.mark.parametrize("name", ["textures.xml", "lights.xml", "blend.xml"])
def test_the_generic_program_in_its_gpu_form_renders_as_its_own_program(gpu_form, specialised, name):
    scene = load_scene(str(Path(__file__).parent / "scenes" / name)).with_settings(max_depth=8, russian_roulette="off")
    a, b = render(gpu_form, scene), render(specialised, scene)
    assert a.uses_generic_program and a.program is gpu_form.generic(media=False)
    same_image(a, b)


def test_devices_check_refuses_a_generic_program_that_miscounts_samples(backend, tmp_path, monkeypatch):
    """`pathtrace devices --check` renders with the generic programs and checks that every pixel
    kept each of its samples, a count no sound program gets wrong (NVIDIA's driver 580 compiled
    the generic program so that pixels counted a third to three times their samples). Where one
    did not, it says so and marks them: no render uses them, the first image waits for the
    scene's own program, and asking for them is one line."""
    from pathtrace.cli.listing import warm_up
    from pathtrace.device.opencl import generic_refused
    from pathtrace.errors import UserError
    from tests.commands import in_process
    monkeypatch.setenv("PATHTRACE_CACHE", str(tmp_path))      # the marks go here
    assert warm_up(backend)[1] == ""
    read_sum = Renderer.read_sum

    def miscounted(self):
        sums = read_sum(self).copy()
        sums[3, 5, 3] += 1.0
        return sums
    with monkeypatch.context() as m:
        m.setattr(Renderer, "read_sum", miscounted)
        assert warm_up(backend)[1] == "simple: pixels kept 4 to 5 of 4 samples"
        r = in_process("devices", "--check")
    assert r.returncode == 0 and "render wrongly here (simple: pixels kept 4 to 5 of 4 samples)" in r.stdout, r.stdout
    device = backend.device.device
    assert generic_refused(device) and backend.built_generic(False) is None
    r = in_process("devices", "--check")          # again: the mark is reported, nothing rebuilt
    assert r.returncode == 0 and "rendered wrongly at an earlier check" in r.stdout, r.stdout + r.stderr
    with pytest.raises(UserError, match="the generic kernels rendered wrongly on this device"):
        backend.generic(False)
    r = Renderer(backend.with_mode("auto"), load_scene("cornell-box"), SIZE, SIZE)
    assert not r.uses_generic_program
    out = tmp_path / "o.png"
    r = in_process("render", "simple", "-q", "--program", "generic", "--spp", "1", "--size", "8x8", "-o", out)
    errors = [line for line in r.stderr.splitlines() if "error" in line]
    assert r.returncode == 1 and len(errors) == 1 and "rendered wrongly" in errors[0] and not out.exists(), r.stderr
    monkeypatch.setenv("PATHTRACE_CACHE", str(tmp_path / "elsewhere"))
    assert not generic_refused(device) and backend.built_generic(False) is not None


@pytest.mark.parametrize("nee", [True, False])
def test_the_render_kernel_is_launched_ahead_on_pocl_doing_nothing(specialised, nee):
    """On PoCL, which compiles a kernel at its first launch, the path tracer's kernel is launched
    once ahead, as the tree's BVH is there, so that it compiles beside the host's work that follows
    (Renderer.compile_ahead): that launch runs (its arguments are the kernel's), and the renders
    after it are those of a renderer without it, bit for bit."""
    scene = load_scene("cornell-box").with_settings(nee=nee)
    r = Renderer(specialised, scene, SIZE, SIZE)
    assert r.compile_ahead() is not None
    r.launch_ahead(r._features("path"), nee)        # raises if the launch's arguments are not the kernel's
    r.add_samples(16)
    r.finish()
    without = Renderer(specialised, scene, SIZE, SIZE)
    without.compile_ahead = lambda: None
    without.set_scene(scene)
    without.add_samples(16)
    without.finish()
    np.testing.assert_array_equal(r.read_sum(), without.read_sum())


def test_nothing_is_launched_ahead_where_the_first_pass_is_another_kernel(specialised):
    """BDPT's, the continuation queue's, and the counting builds' first launches are other kernels."""
    r = Renderer(specialised, load_scene("cornell-box"), SIZE, SIZE)
    for changes in (dict(integrator="bdpt"), dict(path_queue=1)):
        r.set_settings(**changes)
        assert r.compile_ahead() is None, changes
        r.set_settings(integrator="path", path_queue=0)


def test_a_build_in_the_background_calls_what_comes_first_before_it():
    """Programs.start(after=...): the build's thread calls after() first, and builds once it returns."""
    order, gate = [], threading.Event()
    programs = Programs(lambda features, tune: order.append("build"), "test", False)
    programs.start(Features(), after=lambda: (gate.wait(30), order.append("after")))
    assert programs.under_way(Features()) and order == []
    gate.set()
    programs.get(Features())
    assert order == ["after", "build"]


@pytest.mark.parametrize("expected", [True, False])
def test_on_pocl_a_new_scenes_own_program_builds_after_its_trees_kernels(backend, monkeypatch, expected):
    """PoCL compiles one thing at a time in a process: where a tree is expected (expect_tree), the
    scene's own program, whose build starts beside the tree (start_program), waits for the tree's
    build kernels, compiled ahead (await_kernels_ahead), which the first image needs first; where
    none is, it builds at once."""
    events = []
    monkeypatch.setattr(builder_module, "_builders", {})
    monkeypatch.setattr(builder_module, "_tree_expected", expected)
    launch = builder_module.Builder.launch_ahead
    monkeypatch.setattr(builder_module.Builder, "launch_ahead", lambda self: (launch(self), events.append("tree's kernels")))
    auto = building_with(backend, lambda features, tune: (events.append("program"), backend.program_for(features, tune))[1],
                         generic=False)
    Renderer(auto, load_scene("cornell-box"), SIZE, SIZE)
    assert events == (["tree's kernels", "program"] if expected else ["program"])
