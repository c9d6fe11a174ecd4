"""The Python API (app/api.py, docs/python.md): each public function, its errors as UserError,
and re-rendering a changed scene without compiling it again."""

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import pathtrace
from pathtrace.errors import UserError
from pathtrace.io.images import read_hdr
from pathtrace.io.tonecurve import tonemap as display

ROOT = Path(__file__).resolve().parent.parent
DEVICE = os.environ.get("PATHTRACE_TEST_DEVICE", "cpu")
SIZE = (48, 27)


def render(scene, **kwargs):
    return pathtrace.render(scene, size=kwargs.pop("size", SIZE), device=DEVICE, **kwargs)


def small_scene(rho=0.5, le=4.0):
    """A diffuse sphere under an emissive one, in dicts of the TOML format."""
    return {
        "camera": {"eye": [0, 1, 6], "look_at": [0, 0.5, 0], "vfov": 40},
        "environment": {"color": [0.1, 0.1, 0.1]},
        "render": {"width": 32, "height": 18, "spp": 8},
        "materials": {"ball": {"type": "diffuse", "rho_d": [rho, rho, rho]},
                      "lamp": {"type": "emitter", "Le": [le, le, le]}},
        "spheres": [{"center": (0, 0.5, 0), "radius": 1.0, "material": "ball", "name": "ball"},
                    {"center": np.array([0.0, 4.0, 1.0]), "radius": np.float32(0.5), "material": "lamp"}],
    }


def test_import_is_headless_and_lazy():
    """`import pathtrace` loads nothing heavy; a render loads NumPy and PyOpenCL but no GL, GUI
    or Ray package."""
    code = ("import sys, pathtrace; print(sorted(m for m in ('numpy', 'pyopencl') if m in sys.modules)); "
            f"pathtrace.render('simple', spp=1, size=(8, 6), device={DEVICE!r}); "
            "print(sorted(m for m in ('moderngl', 'glfw', 'imgui_bundle', 'OpenGL', 'ray') if m in sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split("\n")[:2] == ["[]", "[]"]


def test_the_subpackages_docs_name_are_attributes_of_a_fresh_import():
    """docs/python.md's pathtrace.cameras.CAMERAS, pathtrace.lights.PointLight and the like work
    right after `import pathtrace`, as attributes imported on first use."""
    code = ("import sys, pathtrace; assert 'pathtrace.cameras' not in sys.modules; "
            "print('perspective' in pathtrace.cameras.CAMERAS, pathtrace.lights.PointLight.__name__, "
            "pathtrace.filters.PixelFilter.__name__, pathtrace.shapes.Shape.__name__)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["True", "PointLight", "PixelFilter", "Shape"]


def test_public_names():
    for name in pathtrace.__all__:
        assert getattr(pathtrace, name) is not None
    assert "render" in dir(pathtrace)
    with pytest.raises(AttributeError):
        pathtrace.no_such_name


def test_load_takes_names_and_files():
    assert pathtrace.load("simple").name == "simple"
    assert len(pathtrace.load(ROOT / "tests" / "scenes" / "cbox.xml").meshes) > 0
    with pytest.raises(UserError, match="neither a scene file nor a built-in"):
        pathtrace.load("no-such-scene")


def test_load_dict_renders_as_the_same_toml_file():
    """A TOML file's tables given as dicts, its mesh files found relative to `folder`: the same
    image, bit for bit."""
    path = ROOT / "assets" / "scenes" / "teapot.toml"
    data = tomllib.loads(path.read_text())
    from_dict = pathtrace.load_dict(data, "teapot", folder=path.parent)
    np.testing.assert_array_equal(render(from_dict, spp=2), render(pathtrace.load(path), spp=2))


def test_load_dict_errors_name_the_field():
    data = small_scene()
    data["spheres"][0]["radius"] = -1
    with pytest.raises(UserError, match=r"^scene dict 'mine': spheres\[0\]\.radius: must be positive"):
        pathtrace.load_dict(data, "mine")
    with pytest.raises(UserError, match="must be a dict"):
        pathtrace.load_dict([1, 2])


def test_render_returns_float32_rgb_and_is_deterministic():
    scene = pathtrace.load_dict(small_scene())
    image = render(scene, spp=4, seed=3)
    assert image.shape == (SIZE[1], SIZE[0], 3) and image.dtype == np.float32
    assert np.all(np.isfinite(image)) and image.mean() > 0
    np.testing.assert_array_equal(image, render(scene, spp=4, seed=3))
    assert not np.array_equal(image, render(scene, spp=4, seed=4))
    # the scene's own settings where none are given
    assert pathtrace.render(scene, device=DEVICE).shape == (18, 32, 3)


def test_render_with_aovs():
    scene = pathtrace.load_dict(small_scene())
    out = render(scene, spp=2, aovs=("albedo", "depth", "normal"))
    assert list(out) == ["image", "albedo", "depth", "normal"]
    assert out["albedo"].shape == out["normal"].shape == out["image"].shape
    assert out["depth"].shape == out["image"].shape[:2]
    # the sphere's albedo at the centre pixel, and its distance: eye (0, 1, 6) to the sphere of
    # radius 1 around (0, 0.5, 0), along the ray through the centre of the image
    h, w = out["depth"].shape
    np.testing.assert_allclose(out["albedo"][h // 2, w // 2], 0.5, atol=1e-6)
    eye, centre = np.array([0, 1, 6.0]), np.array([0, 0.5, 0])
    d = (centre - eye) / np.linalg.norm(centre - eye)
    oc = eye - centre
    b = d @ oc
    t = -b - np.sqrt(b * b - (oc @ oc - 1))
    assert abs(out["depth"][h // 2, w // 2] - t) < 0.05 * t
    with pytest.raises(UserError, match="aovs"):
        render(scene, aovs=("albedo", "beauty"))


@pytest.mark.parametrize("kwargs, message", [
    (dict(spp=0), "spp"), (dict(spp=1.5), "spp"), (dict(size=(0, 10)), "size"), (dict(size=(10,)), "size"),
    (dict(size=(20000, 10)), "size"), (dict(seed=-1), "seed"), (dict(rr="sometimes"), "rr"),
    (dict(rr="off", max_depth=0), "rr 'off' needs max_depth"), (dict(device="no-such-device"), "^device: no OpenCL device matches .no-such-device."),
    (dict(device=[2.5]), "device: give a device spec"), (dict(device=True), "device: give a device spec"),
    (dict(steps=[4, 2]), "steps"),
    (dict(steps=[2, 8], spp=4), "steps: 8 is more samples per pixel than spp \\(4\\)"),
    # a callback that is not one: a TypeError from inside the render before
    (dict(phases=5), "^phases: give a function or None, got 5$"),
    (dict(build_progress="x"), "^build_progress: give a function or None, got 'x'$"),
    (dict(progress=5), "^progress: give True, False or a function, got 5$"),
])
def test_bad_arguments_are_one_line_user_errors(kwargs, message):
    scene = pathtrace.load_dict(small_scene())
    with pytest.raises(UserError, match=message) as e:
        if "steps" in kwargs:
            list(pathtrace.progressive(scene, device=DEVICE, **kwargs))
        else:
            pathtrace.render(scene, **{"device": DEVICE, **kwargs})
    assert "\n" not in str(e.value)


def test_a_device_index_may_be_a_number():
    """device=0 (a NumPy integer too) is the index `pathtrace devices` lists, as device="0" is."""
    scene = pathtrace.load_dict(small_scene())
    image = pathtrace.render(scene, spp=1, size=(8, 6), device="0")
    for index in (0, np.int64(0), [0]):
        np.testing.assert_array_equal(pathtrace.render(scene, spp=1, size=(8, 6), device=index), image)


def test_a_filter_that_is_not_one_and_a_camera_type_that_is_none_are_one_line():
    """A string as the settings' filter said "'str' object has no attribute 'check'"; an unknown
    camera type was a bare KeyError (a new user's run, 2026-12-03)."""
    scene = pathtrace.load_dict(small_scene())
    with pytest.raises(UserError, match="^camera.as_type: no camera type 'bogus' \\(types: orthographic, perspective"):
        scene.camera.as_type("bogus")
    scene.settings.filter = "box"
    with pytest.raises(UserError, match="^scene.settings.filter: give a pathtrace.filters.PixelFilter .*, got 'box'$"):
        render(scene, spp=1, size=(8, 8))


def test_a_numpy_number_is_shown_as_its_number_in_a_message():
    """NumPy 2's repr gave "got np.int32(99)" (a new user's run, 2026-12-03)."""
    from pathtrace.errors import short
    assert (short(np.int32(99)), short(np.float64(1.5)), short(np.bool_(True))) == ("99", "1.5", "true")
    scene = pathtrace.load_dict(small_scene())
    scene.sphere_material[0] = np.int32(99)
    with pytest.raises(UserError, match=r"^scene.sphere_material: material rows must be integers from 0 to \d+, got 99$"):
        render(scene, spp=1, size=(8, 8))


def test_a_changed_scene_is_rendered_without_compiling_it_again():
    """Camera, material, environment and settings changes reuse the compiled scene (its BVH
    stays) and give the image a fresh scene with those changes gives; moving geometry compiles
    anew."""
    scene = pathtrace.load_dict(small_scene())
    render(scene, spp=2)
    prepared = scene._prepared
    bvh = prepared.group.compiled.bvh

    scene.camera.eye = np.array([1.0, 2.0, 5.0])
    scene.materials["ball"] = pathtrace.material({"type": "diffuse", "rho_d": [0.9, 0.2, 0.1]})
    lamp = scene.materials["lamp"]
    lamp.emission = lamp.emission * 2
    scene.materials["lamp"] = lamp
    scene.environment.intensity = 3.0
    changed = render(scene, spp=2, max_depth=3)
    assert scene._prepared is prepared and prepared.group.compiled.bvh is bvh

    fresh = pathtrace.load_dict(small_scene(le=8.0))
    fresh.camera.eye = np.array([1.0, 2.0, 5.0])
    fresh.materials["ball"] = pathtrace.material({"type": "diffuse", "rho_d": [0.9, 0.2, 0.1]})
    fresh.environment.intensity = 3.0
    np.testing.assert_array_equal(changed, render(fresh, spp=2, max_depth=3))

    scene.spheres[0, 1] += 0.25
    moved = render(scene, spp=2, max_depth=3)
    assert scene._prepared is not prepared
    assert not np.array_equal(moved, changed)


def test_changed_lights_filter_and_camera_type_are_rendered_as_a_fresh_scene_renders_them():
    """Delta lights, the pixel filter, the light sampler and the thin lens reach the devices
    without a new compile, as a fresh scene with them renders."""
    from pathtrace.filters import PixelFilter
    from pathtrace.lights import PointLight

    def change(s):
        s.lights.append(PointLight([0.5, 2.0, 1.0], [3.0, 2.0, 1.0]))
        s.lights[-1].check()
        s.camera = s.camera.as_type("thinlens", aperture_radius=0.2, focus_distance=4.0)
        s.settings.filter = PixelFilter("tent")
        s.settings.light_sampler = "tree"
    scene = pathtrace.load_dict(small_scene())
    before = render(scene, spp=2)
    prepared = scene._prepared
    change(scene)
    changed = render(scene, spp=2)
    assert scene._prepared is prepared and not np.array_equal(changed, before)
    fresh = pathtrace.load_dict(small_scene())
    change(fresh)
    np.testing.assert_array_equal(changed, render(fresh, spp=2))
    scene.lights[-1].intensity = np.array([6.0, 4.0, 2.0])
    assert not np.array_equal(render(scene, spp=2), changed)


def test_progressive_yields_each_step_and_ends_at_the_render():
    scene = pathtrace.load_dict(small_scene())
    snapshots = list(pathtrace.progressive(scene, spp=6, size=SIZE, device=DEVICE))
    assert [s.spp for s in snapshots] == [1, 2, 4, 6]
    assert all(b.seconds >= a.seconds for a, b in zip(snapshots, snapshots[1:]))
    np.testing.assert_allclose(snapshots[-1].image, render(scene, spp=6), rtol=1e-5, atol=1e-6)
    steps = [s.spp for s in pathtrace.progressive(scene, steps=[3, 5], size=SIZE, device=DEVICE, aovs="albedo")]
    assert steps == [3, 5]
    assert snapshots[0]._repr_png_()[:4] == b"\x89PNG"


def test_progress_is_reported():
    seen = []
    render(pathtrace.load_dict(small_scene()), spp=5, progress=seen.append)
    assert seen[0] == 0 and seen[-1] == 5 and seen == sorted(seen)


def test_tonemap_write_and_show(tmp_path):
    image = np.random.default_rng(1).uniform(0, 2, (6, 8, 3)).astype(np.float32)
    srgb = pathtrace.tonemap(image, exposure=-1, curve="aces")
    assert srgb.dtype == np.uint8 and srgb.shape == (6, 8, 3)
    np.testing.assert_array_equal(srgb, np.round(display(image, -1, "aces") * 255).astype(np.uint8))
    pathtrace.write(tmp_path / "a.exr", image)
    np.testing.assert_array_equal(read_hdr(tmp_path / "a.exr", "a"), image)
    pathtrace.write(tmp_path / "d.exr", image[..., 0])           # a depth: grey
    np.testing.assert_array_equal(read_hdr(tmp_path / "d.exr", "d")[..., 2], image[..., 0])
    pathtrace.write(tmp_path / "a.png", image)
    assert (tmp_path / "a.png").read_bytes()[:4] == b"\x89PNG"
    assert pathtrace.show(image)._repr_png_()[:4] == b"\x89PNG"
    for bad in (lambda: pathtrace.tonemap(image, curve="filmic"), lambda: pathtrace.tonemap(image, exposure=1e9),
                lambda: pathtrace.write(tmp_path / "b.png", np.zeros((4, 4, 2))),
                lambda: pathtrace.write(tmp_path / "b.txt", image), lambda: pathtrace.show(np.zeros(3))):
        with pytest.raises(UserError):
            bad()
    # tonemap's own uint8 output given back as radiance, 0-255 (a white image): refused
    with pytest.raises(UserError, match="^image: an array of uint8 is a display image, not radiance"):
        pathtrace.write(tmp_path / "b.png", srgb)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.exr", "a.png", "d.exr"]


def test_images_with_nan_or_infinity_are_refused_naming_the_argument_and_pixel(tmp_path, recwarn):
    image = np.zeros((4, 5, 3))
    image[2, 3, 1] = np.nan
    huge = np.zeros((4, 5))
    huge[1, 0] = 1e39                         # finite in float64, infinite in float32
    calls = {"image": [lambda: pathtrace.tonemap(image), lambda: pathtrace.write(tmp_path / "a.png", image),
                       lambda: pathtrace.write(tmp_path / "a.exr", image), lambda: pathtrace.show(image),
                       lambda: pathtrace.denoise(image)],
             "albedo": [lambda: pathtrace.denoise(np.zeros((4, 5, 3)), albedo=image)]}
    for name, bad in [(name, call) for name, group in calls.items() for call in group]:
        with pytest.raises(UserError, match=rf"^{name}: 1 pixel\(s\) hold NaN or infinity .*, the first at x=3, y=2$"):
            bad()
    with pytest.raises(UserError, match=r"^image: 1 pixel\(s\) hold NaN or infinity .*, the first at x=0, y=1$"):
        pathtrace.write(tmp_path / "b.exr", huge)
    assert not list(tmp_path.iterdir()) and not recwarn.list        # nothing written, nothing from NumPy


def test_denoise():
    scene = pathtrace.load("demo")
    out = pathtrace.render(scene, spp=2, size=(64, 36), device=DEVICE, aovs=("albedo", "normal"))
    denoised = pathtrace.denoise(out["image"], out["albedo"], out["normal"])
    assert denoised.shape == out["image"].shape and np.all(np.isfinite(denoised))
    # smoother: neighbouring pixels differ less than in the noisy image
    roughness = lambda x: np.abs(np.diff(x, axis=1)).mean()     # noqa: E731
    assert roughness(denoised) < 0.7 * roughness(out["image"])
    assert pathtrace.denoise(out["image"]).shape == out["image"].shape
    with pytest.raises(UserError, match="shape"):
        pathtrace.denoise(out["image"], out["albedo"][:10])
    with pytest.raises(UserError, match="quality"):
        pathtrace.denoise(out["image"], quality="best")


def test_devices():
    found = pathtrace.devices()
    assert found and all(d.kind in ("GPU", "CPU", "other") for d in found)
    assert any(d.kind == "CPU" for d in found)


def test_material_errors_name_the_field():
    with pytest.raises(UserError, match=r"material dict: material\.alpha"):
        pathtrace.material({"type": "roughconductor", "alpha": -1})
    scene = pathtrace.load_dict(small_scene())
    with pytest.raises(UserError, match="no material named 'gold'"):
        scene.materials["gold"]
    with pytest.raises(UserError, match="no material 7"):
        scene.materials[7]


def test_the_path_queue_setting_reaches_a_prepared_scene():
    """settings.path_queue changed between renders of one scene takes effect on its devices (the
    continuation queue's buffers sized anew), and the image is the one without it, but for the
    order of each pixel's float32 sums."""
    scene = pathtrace.load_dict(small_scene())
    plain = render(scene, spp=4, max_depth=6)
    prepared = scene._prepared
    scene.settings.path_queue = 1
    queued = render(scene, spp=4, max_depth=6)
    assert scene._prepared is prepared
    assert all(r.settings.path_queue == 1 for r in prepared.group.renderers)
    np.testing.assert_allclose(queued, plain, rtol=1e-5, atol=1e-6)



@pytest.mark.parametrize("value", [-2, 65, 1.5, -1.0, "2", "auto", None, True])
def test_a_bad_path_queue_setting_is_one_user_error(value):
    scene = pathtrace.load_dict(small_scene())
    scene.settings.path_queue = value
    with pytest.raises(UserError, match=r"settings.path_queue \(or PATH_QUEUE_AUTO\): give an integer from 0 to 64"):
        render(scene, spp=1)


@pytest.mark.specialised
def test_auto_chooses_its_plan_for_the_whole_render(monkeypatch):
    """"auto" chooses for the render's samples, so that a long render runs its trials (which a
    render shorter than them skips), and render(), which takes one snapshot, of them all, has
    the trials' samples kept (from index 0)."""
    from pathtrace.rendering.renderer import Renderer
    asked = []
    choose = Renderer.choose_queue_plan
    monkeypatch.setattr(Renderer, "choose_queue_plan", lambda self, samples, trials=None, first=None:
                        (asked.append((samples, first)), choose(self, samples, trials, first)))
    scene = pathtrace.load_dict(small_scene())
    scene.settings.path_queue = pathtrace.PATH_QUEUE_AUTO
    render(scene, spp=200, max_depth=6)
    assert asked and asked[0] == (200, 0)


@pytest.mark.specialised
def test_the_path_queue_setting_takes_auto():
    """pathtrace.PATH_QUEUE_AUTO: on PoCL, no queue (and no trial renders), so the image is the
    one without it."""
    scene = pathtrace.load_dict(small_scene())
    plain = render(scene, spp=4, max_depth=6)
    scene.settings.path_queue = pathtrace.PATH_QUEUE_AUTO
    auto = render(scene, spp=4, max_depth=6)
    assert all(r.queue_plan() == (0, False) and not r.plan_seconds for r in scene._prepared.group.renderers)
    assert pathtrace.queue_plans(scene) == ["no queue"]
    np.testing.assert_array_equal(auto, plain)
    scene.settings.path_queue = 0
    render(scene, spp=1)
    assert pathtrace.queue_plans(scene) == [] and pathtrace.queue_plans(pathtrace.load_dict(small_scene())) == []


@pytest.mark.specialised
def test_programs_used_says_where_the_generic_program_drew_samples(monkeypatch):
    backend = pathtrace.api.open_devices(DEVICE)[0]
    scene = pathtrace.load_dict(small_scene())
    render(scene, spp=4)
    assert pathtrace.programs_used(scene) == []              # the tests' mode: the scene's own
    monkeypatch.setattr(backend, "mode", "generic")
    generic = pathtrace.load_dict(small_scene())
    render(generic, spp=4)
    assert pathtrace.programs_used(generic) == [f"{backend.device.name}: 4 spp from the generic kernels"]
    assert pathtrace.programs_used(pathtrace.load_dict(small_scene())) == []


@pytest.mark.specialised
def test_a_renders_first_program_is_built_for_its_own_settings():
    """render(nee=False) of a scene whose own settings say NEE: one program, the estimator's the
    render asked for, where the group had been made with the scene's first."""
    from dataclasses import replace
    data = small_scene()
    data["render"]["filter"] = {"type": "gaussian", "stddev": 0.4}    # programs no other test builds
    scene = pathtrace.load_dict(data)
    assert scene.settings.nee
    render(scene, spp=2, nee=False)
    r = scene._prepared.group.renderers[0]
    assert r.program.kernel_names == "render" and not r.settings.nee
    features = r.compiled.features(r.settings, r.camera)
    for kernels in ("render_nee", "render"):
        asked = replace(features, kernels=kernels)
        assert (r.backend.programs.built(asked) is not None) == (kernels == "render")
        assert not r.backend.programs.under_way(asked)


def test_a_scenes_lights_reassigned_between_renders_are_rendered():
    """The prepared renderers render the user's scene as it is at each render, not a copy of it
    taken at the first."""
    from pathtrace.lights import DELTA_LIGHTS
    lamp = DELTA_LIGHTS["point"].from_values({"position": np.array([0.0, 1.0, 0.0]), "intensity": np.full(3, 50.0)})
    scene = pathtrace.load("cornell-box")
    dark = render(scene, spp=4, size=(16, 16))
    scene.lights = [lamp]
    lit = render(scene, spp=4, size=(16, 16))
    fresh = pathtrace.load("cornell-box")
    fresh.lights = [lamp]
    expected = render(fresh, spp=4, size=(16, 16))
    assert lit.mean() > 1.5 * dark.mean()
    np.testing.assert_allclose(lit, expected, rtol=1e-5, atol=1e-6)


def test_materials_meshes_lights_and_textures_read_as_mappings():
    """A notebook lists a scene's parts as it lists a dict's: keys, items, len, in."""
    scene = pathtrace.load("cornell-box")
    assert list(scene.materials) == scene.materials.keys() == ["white", "red", "green", "light"]
    assert len(scene.materials) == 4 and "red" in scene.materials and 3 in scene.materials
    assert "blue" not in scene.materials and 4 not in scene.materials and True not in scene.materials
    name, red = scene.materials.items()[1]
    assert name == "red" and red.type == "diffuse" and np.allclose(red.params["rho_d"], scene.materials["red"].params["rho_d"])
    assert [m.type for m in scene.materials.values()] == [scene.materials[k].type for k in scene.materials]
    assert scene.meshes.keys()[-1] == "tall block" and "tall block" in scene.meshes
    assert scene.meshes["tall block"] is scene.meshes[-1] and dict(scene.meshes.items())["walls"] is scene.meshes[0]
    with pytest.raises(UserError, match="no mesh named 'roof' \\(named: walls, left wall"):
        scene.meshes["roof"]
    assert scene.with_settings(spp=1).meshes is scene.meshes
    unnamed = pathtrace.load(ROOT / "tests" / "scenes" / "lights.xml")
    assert unnamed.materials.keys() == [0, 1, 2] and unnamed.lights.keys() == ["point 0", "spot 1", "directional 2"]
    assert unnamed.lights["spot 1"] is unnamed.lights[1]
    textured = pathtrace.load(ROOT / "assets" / "scenes" / "teapot-textured.toml")
    assert sorted(textured.textures) == ["glaze", "tiles"] and textured.textures["glaze"].type == "checkerboard"


def test_reprs_are_one_short_line():
    """repr() of each public object says what it holds in a line, never dumping its arrays."""
    scene = pathtrace.load("teapot")        # 126,050 triangles
    text = repr(scene)
    assert text.startswith("<Scene 'teapot': 0 spheres, 3 meshes (126050 triangles), 2 materials, 0 delta lights; "
                           "bounds (-200, 0, -200) to (200, 6.165, 200); camera at (15, 8.5, 11.5) looking at (0, 2.4, 0); "
                           "1280x720, 256 spp; from ")
    lower, upper = scene.bounds()
    vertices = np.concatenate([m.vertices for m in scene.meshes])
    assert np.array_equal(lower, vertices.min(0)) and np.array_equal(upper, vertices.max(0))
    image = np.zeros((36, 64, 3), np.float32)
    objects = [scene, scene.materials, scene.meshes, scene.meshes[0], scene.lights, scene.camera, scene.environment,
               pathtrace.load(ROOT / "tests" / "scenes" / "textures.xml").textures["texture 0"],
               pathtrace.show(image), pathtrace.Snapshot(4, 0.5, image, {})]
    for obj in objects:
        text = repr(obj)
        assert "\n" not in text and len(text) < 400 and "array" not in text and "..." not in text[:-1], text
    body = scene.meshes["teapot body"]
    assert repr(body) == (f"<Mesh 'teapot body': {len(body.vertices)} vertices, {len(body.faces)} triangles, material 0, "
                          f"smooth normals, uvs, from {body.source}>")
    assert repr(pathtrace.show(image)) == "<Picture 64x36, exposure 0, standard tone curve>"
    assert repr(scene.camera) == "<Camera perspective at (15, 8.5, 11.5) looking at (0, 2.4, 0), up (0, 1, 0), vfov 30>"


@pytest.mark.parametrize("source, generic", [("cbox.pbrt", "scene-v4.pbrt"), ("lights.xml", "scene.xml")])
def test_a_file_of_a_generic_name_is_named_after_its_folder(tmp_path, source, generic):
    """Bitterli's scenes are all scene-v4.pbrt or scene.xml: the folder says which."""
    (tmp_path / "coffee" / "pbrt").mkdir(parents=True)
    (tmp_path / "coffee" / generic).write_text((ROOT / "tests" / "scenes" / source).read_text())
    (tmp_path / "coffee" / "pbrt" / generic).write_text((ROOT / "tests" / "scenes" / source).read_text())
    assert pathtrace.load(tmp_path / "coffee" / generic).name == "coffee"
    assert pathtrace.load(tmp_path / "coffee" / "pbrt" / generic).name == "coffee"     # Bitterli's layout
    assert pathtrace.load(ROOT / "tests" / "scenes" / source).name == source.split(".")[0]


def test_devices_open_in_a_thread_of_their_own_and_give_their_error_when_asked(monkeypatch):
    """DevicesOpening (the render command's and the viewer's, begun before the scene is read):
    the backends open_devices keeps, given as soon as they are open, then their BVH build
    kernels built in the same thread (here held until the backends are given); a device that
    cannot be opened is the same one line, raised where the backends are asked for."""
    import threading
    import time

    from pathtrace import api
    from pathtrace.compiler import builder as bvh
    monkeypatch.setattr(bvh, "_builders", {})        # none built by the tests before this one
    held, builder_for = threading.Event(), bvh.builder_for
    monkeypatch.setattr(bvh, "builder_for", lambda queue=None, ahead=False: builder_for(queue, ahead) if held.wait(30) else None)
    opening = api.DevicesOpening(DEVICE)
    backends = opening.result()
    assert backends == api.open_devices(DEVICE) and opening.seconds > 0 and not bvh._builders
    held.set()
    deadline = time.monotonic() + 30
    while not all(b.queue in bvh._builders for b in backends) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert all(b.queue in bvh._builders for b in backends)
    failing = api.DevicesOpening("no-such-device")
    with pytest.raises(UserError, match="no OpenCL device matches 'no-such-device'"):
        failing.result()


def test_a_scene_compiles_while_its_devices_open(monkeypatch, tmp_path):
    """render() given a DevicesOpening (what `pathtrace render` passes): the scene is compiled,
    its tree read from the BVH cache, before the devices are asked for, so that it runs while
    they open; the devices here open only once it has (30 s at most, else none)."""
    import threading

    from pathtrace import api
    from pathtrace.compiler.compiled import CompiledScene
    monkeypatch.setenv("PATHTRACE_BVH_CACHE", str(tmp_path))
    pathtrace.render(pathtrace.load("spheres64k"), spp=1, size=(8, 8), device="cpu")    # fills the BVH cache
    tree_first = threading.Event()
    build_tree = CompiledScene.build_tree

    def noting(compiled, queue=None, cached_only=False, when_bvh_built=None):
        built = build_tree(compiled, queue, cached_only, when_bvh_built)
        if built and cached_only:
            tree_first.set()
        return built
    monkeypatch.setattr(CompiledScene, "build_tree", noting)
    opened = api.open_devices("cpu")
    monkeypatch.setattr(api, "open_devices", lambda device: opened if tree_first.wait(30) else [])
    image = pathtrace.render(pathtrace.load("spheres64k"), spp=1, size=(8, 8), device=api.DevicesOpening("cpu"))
    assert tree_first.is_set() and np.isfinite(image).all() and image.shape == (8, 8, 3)


def test_a_device_spec_asked_for_twice_at_once_opens_once(monkeypatch):
    """A DevicesOpening's thread and a render asking for the same spec at once: the devices are
    opened once, the later call waiting for the first (a second opening would build its own
    kernels on a second context)."""
    import threading
    import time

    from pathtrace import api
    from pathtrace.device import opencl
    opened, choose_devices = [], opencl.choose_devices

    def slow(specs, *args, **kwargs):
        opened.append(specs)
        time.sleep(0.3)
        return choose_devices(specs, *args, **kwargs)
    monkeypatch.setattr(opencl, "choose_devices", slow)
    monkeypatch.setattr(api, "_backends", {})
    got = []
    threads = [threading.Thread(target=lambda: got.append(api.open_devices(DEVICE))) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(opened) == 1 and len(got) == 2 and got[0] is got[1]


def test_a_material_table_is_compared_by_its_bytes():
    """Whether a scene's materials changed since its devices were set up (a render again, an
    edit): the rows' bytes, so that a table of a million rows is compared in milliseconds and a
    NaN in a field is not a change every time."""
    from pathtrace.api import _same_rows
    from pathtrace.materials import Material, MaterialTable
    table = MaterialTable()
    for k in range(3):
        table.add(Material("diffuse", {"rho_d": 0.1 * (k + 1)}))
    rows = table.rows.copy()
    assert _same_rows(table.rows, rows)
    rows["p0"][1, 0] = np.nan
    same_nan = rows.copy()
    assert _same_rows(rows, same_nan) and not _same_rows(table.rows, rows)
    assert not _same_rows(table.rows, table.rows[:2])


@pytest.mark.parametrize("change,field", [
    ({"rho_d": [2.0, 0.5, 0.5]}, "rho_d"), ({"rho_d": [-1.0, 0.5, 0.5]}, "rho_d"),
    ({"rho_d": [np.inf, 0.5, 0.5]}, "rho_d"), ({"rho_d": [np.nan, 0.5, 0.5]}, "rho_d"),
    ({"emission": [np.nan, 1.0, 1.0]}, "emission"), ({"emission": [-1.0, 1.0, 1.0]}, "emission"),
    ({"emission": [1e39, 1.0, 1.0]}, "emission"),       # beyond float32: it blamed the scene's file
    ({"blend": 2.0}, "rho_d"),
])
def test_a_material_changed_through_the_api_is_checked_as_a_file_is(change, field):
    """A Material read from a scene, changed and set back (scene.materials[key] = m) is held to
    its BSDF's declared ranges, as the readers hold a file's values: one UserError naming the
    field, never a surface giving back more light than it receives or a NaN image."""
    from pathtrace.materials import Material
    scene = pathtrace.load("cornell-box")
    m = scene.materials["white"]
    if "emission" in change:
        m.emission = np.array(change["emission"])
    elif "blend" in change:
        m = Material("blendbsdf", {"weight": 0.5}, components=(
            Material("diffuse", {"rho_d": np.full(3, change["blend"])}), Material("diffuse", {"rho_d": np.full(3, 0.5)})))
    else:
        m.params = dict(m.params, rho_d=np.array(change["rho_d"]))
    with pytest.raises(UserError) as e:
        scene.materials["white"] = m
    assert f"materials['white']: {field}:" in str(e.value) and "\n" not in str(e.value)


def test_every_material_read_from_a_file_can_be_set_back_unchanged():
    """The API's check compares as the kernels hold values, in float32: a value read back from
    its row (a thickness of 1e-06 is 9.9999997e-07 there) is within the bound it was read under."""
    for name in ("tests/scenes/meshes-larger.pbrt", "tests/scenes/roughplastic.xml", "materials", "cornell-box"):
        scene = pathtrace.load(str(ROOT / name) if "/" in name else name)
        for key in scene.materials.keys():
            scene.materials[key] = scene.materials[key]


def test_a_nan_emission_in_a_materials_row_is_named_as_not_a_number():
    """A row changed beneath the API's checks (its packed array written directly) still stops at
    the compile, with a line that says what the value is."""
    from pathtrace.compiler.compiled import check_radiance
    scene = pathtrace.load("cornell-box")
    scene.materials.rows["emission"][scene.materials.index("light"), 0] = np.nan
    with pytest.raises(UserError, match=r"material 'light': an emitted radiance that is not a number \(NaN\)$"):
        check_radiance(scene)


def test_a_misspelt_setting_is_refused():
    """settings.sppp = 4 would change nothing: an AttributeError naming the settings there are,
    as a camera's misspelt field gives."""
    scene = pathtrace.load("simple")
    with pytest.raises(AttributeError, match="render settings have no 'sppp'.*spp"):
        scene.settings.sppp = 4
    scene.settings.spp = 4
    assert scene.settings.spp == 4
