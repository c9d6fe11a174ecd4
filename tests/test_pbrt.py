"""The pbrt-v4 reader (app/scene/pbrt): each convention of pbrt-v4's format against what it
means, a translated Mitsuba reference scene against Mitsuba's render, and bad input."""

import gzip
import math
import os
from pathlib import Path

import numpy as np
import pytest

from pathtrace.errors import UserError
from pathtrace.materials.optics import CONDUCTORS
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
import pathtrace.scene.instances as instancing
from pathtrace.scene.instances import flattened_meshes
from pathtrace.scene.pbrt.equal_area import sphere_to_square
from pathtrace.scene.transform import scaling, translation
from pathtrace.scene.spectra import blackbody_rgb, named_spectrum, reflectance_rgb, sampled
from tests.commands import in_process
from tests.stats import z_test
from tests.test_reference import REFERENCE_BIAS

SCENES = Path(__file__).parent / "scenes"
FLOOR = 'Shape "trianglemesh" "point3 P" [ -1 0 -1  1 0 -1  1 0 1  -1 0 1 ] "integer indices" [ 0 2 1  0 3 2 ]\n'


def scene(tmp_path, body, head="", name="s.pbrt"):
    path = tmp_path / name
    path.write_text(head + "\nWorldBegin\n" + body)
    return load_scene(str(path))


def fails(tmp_path, text, name="s.pbrt") -> str:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    message = str(e.value)
    assert "\n" not in message
    return message


# -- a Mitsuba reference, translated --

@pytest.mark.parametrize("name,two_level", [("cbox", False), ("cbox", True), ("meshes-smaller", False),
                                            ("meshes-larger", False), ("metals", False), ("equal-area", False)])
def test_translations_of_mitsuba_scenes_render_as_mitsuba_renders_the_xml(backend, monkeypatch, name, two_level):
    """tests/scenes/<name>.pbrt is <name>.xml in pbrt's terms (handedness, the fov's axis,
    transform order, maxdepth, instances, a PLY mesh, a sphere, an infinite light, pbrt's named
    metal spectra for Mitsuba's named metals, an infinite light's equal-area map against the
    lat-long map of the same sky): its render passes the Z-test against Mitsuba 3's render of
    the XML. cbox.pbrt's instanced boxes render so both as copies and through the two-level BVH."""
    monkeypatch.setattr(instancing, "FLATTEN_MAX", -1 if two_level else instancing.FLATTEN_MAX)
    ref = np.load(Path(__file__).parent / "references" / f"{name}.npz")
    pbrt = load_scene(str(SCENES / f"{name}.pbrt"))
    assert pbrt.settings.max_depth == int(ref["max_depth"]) == 8
    h, w, _ = ref["mean"].shape
    assert (pbrt.settings.width, pbrt.settings.height) == (w, h)
    r = Renderer(backend, pbrt.with_settings(russian_roulette="off"), w, h)
    assert r.compiled.two_level == two_level
    for _ in range(8):
        r.add_samples(128)
    r.finish()
    ok, p, threshold = z_test(r.mean(), r.variance() / r.samples, ref["mean"], ref["var_of_mean"], block=4,
                              rel_floor=REFERENCE_BIAS.get(name, 1e-5))
    assert ok, f"smallest p-value {p:.3g} below the Sidak threshold {threshold:.3g}"


# -- conventions --

def test_a_plain_lookat_is_a_mirrored_camera_and_scale_minus_x_undoes_it(tmp_path):
    look = "LookAt 0 1 5  0 1 0  0 1 0\nCamera \"perspective\"\n"
    plain = scene(tmp_path, FLOOR, look).camera
    assert plain.mirrored
    forward, right, up = plain.basis(1.0)
    assert np.allclose(forward, [0, 0, -1]) and up[1] > 0
    # pbrt's image right is camera +x = cross(up, dir) = -x here; pathtrace's unmirrored right is +x
    assert right[0] < 0
    flipped = scene(tmp_path, FLOOR, "Scale -1 1 1\n" + look).camera
    assert not flipped.mirrored and flipped.basis(1.0)[1][0] > 0


@pytest.mark.parametrize("width,height", [(200, 100), (100, 200)])
def test_fov_spans_the_shorter_image_axis(tmp_path, width, height):
    head = (f'Film "rgb" "integer xresolution" {width} "integer yresolution" {height}\n'
            'LookAt 0 1 5  0 1 0  0 1 0\nCamera "perspective" "float fov" 40\n')
    camera = scene(tmp_path, FLOOR, head).camera
    half = math.tan(math.radians(camera.vfov) / 2)
    shorter = half if height <= width else half * width / height
    assert shorter == pytest.approx(math.tan(math.radians(20)))


def test_transforms_are_column_major_and_compose_in_the_order_written(tmp_path):
    s = scene(tmp_path, 'AttributeBegin\nTransform [ 1 0 0 0  0 1 0 0  0 0 1 0  1 2 3 1 ]\n'
                        'Shape "sphere" "float radius" 0.5\nAttributeEnd\n'
                        'AttributeBegin\nTranslate 1 0 0\nScale 2 2 2\nShape "sphere"\nAttributeEnd\n'
                        'AttributeBegin\nTranslate 0 0 5\nConcatTransform [ 1 0 0 0  0 1 0 0  0 0 1 0  0 1 0 1 ]\n'
                        'Shape "sphere"\nAttributeEnd\nShape "sphere" "float radius" 3\n')
    assert np.allclose(s.spheres, [[1, 2, 3, 0.5], [1, 0, 0, 2], [0, 1, 5, 1], [0, 0, 0, 3]])


def test_maxdepth_counts_bounces(tmp_path):
    assert scene(tmp_path, FLOOR, 'Integrator "path" "integer maxdepth" 3\n').settings.max_depth == 4
    assert scene(tmp_path, FLOOR).settings.max_depth == 6            # pbrt's default 5


@pytest.mark.parametrize("kind", ["dielectric", "thindielectric"])
def test_a_dielectric_of_eta_below_one_has_the_denser_medium_outside(tmp_path, kind):
    """pbrt-v4's eta is inside over outside and may lie below 1 (an air bubble in water): its
    DielectricBxDF takes etap = eta or 1 / eta by wo's side. The same interface, its normal
    unturned, has int_ior 1 and ext_ior 1 / eta; taking 1 / eta inside turned the optics over
    (review 2026-11-28, F7)."""
    s = scene(tmp_path, f'Material "{kind}" "float eta" 0.75\n' + FLOOR)
    m = s.materials.get(s.meshes[0].material)
    assert m.type == kind and m.params["int_ior"] == pytest.approx(1.0) and m.params["ext_ior"] == pytest.approx(1 / 0.75)
    assert "0.05" in fails(tmp_path, f'WorldBegin\nMaterial "{kind}" "float eta" 0.05\n' + FLOOR)


def test_a_twosided_area_light_is_one_surface_emitting_from_both_sides(tmp_path):
    """pbrt-v4's DiffuseAreaLight with twoSided: L on both sides of each triangle, which stays
    one triangle (coincident opposite copies let the traversal's rounding pick the side seen;
    review 2026-11-28, F1); tests/test_pbrt_reference.py renders it against pbrt-v4."""
    s = scene(tmp_path, 'AreaLightSource "diffuse" "rgb L" [ 2 2 2 ] "bool twosided" true\n' + FLOOR)
    assert len(s.meshes[0].faces) == 2
    m = s.materials.get(s.meshes[0].material)
    assert m.emits_back and np.allclose(m.emission, 2)
    one = scene(tmp_path, 'AreaLightSource "diffuse"\n' + FLOOR, name="one.pbrt")
    assert not one.materials.get(one.meshes[0].material).emits_back


def test_a_sphere_under_a_non_uniform_transform_is_the_ellipsoid_pbrt_intersects(tmp_path):
    """pbrt-v4 intersects a sphere in its object space, so a non-uniform Scale, in the shape's
    own transform or an instance's, makes an ellipsoid: an analytic sphere under that transform
    (tests/test_sphere_shape.py renders it; tests/test_pbrt_reference.py renders pbrt-v4's
    instancing scene against pbrt-v4). A uniform one, untextured, stays in the sphere range."""
    body = ('AttributeBegin\nTranslate 1 0 0\nScale 1 2 1\nShape "sphere" "float radius" 0.5\nAttributeEnd\n'
            'ObjectBegin "ball"\nShape "sphere" "float radius" 0.5\nObjectEnd\n'
            'AttributeBegin\nTranslate 1 0 0\nScale 1 2 1\nObjectInstance "ball"\nAttributeEnd\n'
            'AttributeBegin\nTranslate 0 3 0\nScale 2 2 2\nObjectInstance "ball"\nAttributeEnd\n')
    s = scene(tmp_path, body)
    assert not s.meshes and np.allclose(s.spheres, [[0, 3, 0, 1]])
    assert [sh.kind for sh in s.shapes] == ["sphere", "sphere"]
    for shape in s.shapes:
        assert shape.params == pytest.approx((0.5, -0.5, 0.5, 2 * np.pi)) and not shape.flip
        np.testing.assert_allclose(shape.to_world, translation([1, 0, 0]) @ scaling([1, 2, -1]))   # z turned: from_pbrt


def test_named_spectra_blackbodies_and_sampled_spectra(tmp_path):
    s = scene(tmp_path, 'Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"\n' + FLOOR)
    m = s.materials.get(s.meshes[0].material)
    assert m.type == "conductor"
    assert np.allclose(m.params["eta"], CONDUCTORS["Au"][0]) and np.allclose(m.params["k"], CONDUCTORS["Au"][1])
    assert named_spectrum("glass-BK7")[0][0] == pytest.approx(1.5168)
    white = blackbody_rgb(6504.0)
    y = 0.2126 * white[0] + 0.7152 * white[1] + 0.0722 * white[2]
    # a 6504 K blackbody lies on the Planckian locus, just below D65 (a little magenta)
    assert y == pytest.approx(1.0, abs=0.01) and np.ptp(white) < 0.1 and white[1] < min(white[0], white[2])
    warm = blackbody_rgb(2700.0)
    assert warm[0] > warm[1] > warm[2]
    constant = sampled(np.array([300.0, 0.4, 900.0, 0.4]))
    assert np.allclose(reflectance_rgb(constant), 0.4)


def test_a_reflectance_texture_beyond_1_is_clamped_where_it_is_evaluated(tmp_path):
    """pbrt-v4 clamps a diffuse reflectance (and a coated one's, and diffuse transmission's
    scaled colours) into [0, 1] as it evaluates it: a texture that may leave [0, 1] is wrapped in
    a clamp texture, one that stays within is not (a scene of such textures compiles no clamp)."""
    import shutil
    shutil.copy(Path(__file__).parent / "scenes" / "textures" / "tiles.png", tmp_path / "tiles.png")
    body = ('Texture "t" "spectrum" "imagemap" "string filename" "tiles.png" "float scale" {scale}\n'
            'Material "{material}" "texture {name}" "t" {more}\nShape "sphere"\n')
    for material, name, scale, clamped, more in (
            ("diffuse", "reflectance", 2, True, ""), ("diffuse", "reflectance", 1, False, ""),
            ("coateddiffuse", "reflectance", 3, True, ""),
            ("diffusetransmission", "transmittance", 1.5, True, '"rgb reflectance" [0 0 0]')):
        m = scene(tmp_path, body.format(scale=scale, material=material, name=name, more=more)).materials.get(0)
        value = next(v for v in m.params.values() if hasattr(v, "kind"))
        assert (value.type == "clamp") == clamped, (material, scale)
        assert value.maximum().max() <= 1 and value.minimum().min() >= 0
    # an image inside a mix is clamped itself, as pbrt-v4's image texture clamps an albedo's rgb:
    # 0.5 min(2 t, 1), not min(t, 1); the mix, within [0, 1], is not clamped again
    m = scene(tmp_path, 'Texture "t" "spectrum" "imagemap" "string filename" "tiles.png" "float scale" 2\n'
                        'Texture "m" "spectrum" "mix" "texture tex1" "t" "rgb tex2" [0 0 0] "float amount" 0.5\n'
                        'Material "diffuse" "texture reflectance" "m"\nShape "sphere"\n').materials.get(0)
    mix = m.params["rho_d"]
    assert mix.type == "mix" and mix.params["tex1"].type == "clamp" and mix.params["tex1"].params["tex"].type == "scale"


def test_a_shapes_alpha_number_beyond_0_and_1_is_taken_as_pbrt_v4_takes_it(tmp_path):
    """pbrt-v4 takes any alpha number: its stochastic test keeps every hit where the alpha is at
    least 1 and none where it is at most 0 (GeometricPrimitive::Intersect), as an opacity
    clamped to [0, 1] does (and which `convert` writes as TOML reads it); an alpha texture beyond
    [0, 1] is refused as in every format."""
    def opacity(alpha, texture=""):
        s = scene(tmp_path, texture + FLOOR.replace("]\n", f"] {alpha}\n"))
        material = s.materials.get(s.meshes[0].material)
        return material.masked, material.opacity
    assert opacity('"float alpha" 1.5') == (False, 1.0)                   # every hit kept
    masked, cut = opacity('"float alpha" -0.5')
    assert masked and cut.params["value"][0] == 0                         # none kept
    assert "'alpha': must lie in [0, 1], got from 0.5 to 2" in fails(
        tmp_path, 'WorldBegin\nTexture "a" "float" "checkerboard" "float tex1" 2 "float tex2" 0.5\n'
        + FLOOR.replace("]\n", '] "texture alpha" "a"\n'))


def test_roughness_is_remapped_as_pbrt_remaps_it(tmp_path):
    def alpha(params):
        s = scene(tmp_path, f'Material "conductor" {params}\n' + FLOOR)
        return s.materials.get(s.meshes[0].material).params["alpha"]
    assert alpha('"float roughness" 0.25') == pytest.approx(0.5)
    assert alpha('"float roughness" 0.25 "bool remaproughness" false') == pytest.approx(0.25)


def test_u_and_v_roughness_are_the_tangent_and_bitangent_alphas(tmp_path):
    """pbrt-v4's uroughness runs along dp/du (its BSDF frame's x), as Mitsuba's alpha_u."""
    for kind in ("conductor", "dielectric"):
        s = scene(tmp_path, f'Material "{kind}" "float uroughness" 0.04 "float vroughness" 0.25\n' + FLOOR)
        m = s.materials.get(s.meshes[0].material)
        assert m.type == "rough" + kind
        assert (m.params["alpha"], m.params["alpha_v"]) == pytest.approx((0.2, 0.5))


def test_fronts_follow_the_normals_or_reverse_orientation(tmp_path):
    """The light's winding faces +y; with normals N pointing down, pbrt's front is down."""
    quad = '"point3 P" [ -1 0 -1  1 0 -1  1 0 1  -1 0 1 ] "integer indices" [ 0 2 1  0 3 2 ]'
    down = '"normal N" [ 0 -1 0  0 -1 0  0 -1 0  0 -1 0 ]'

    def normal(body):
        m = scene(tmp_path, body).meshes[0]
        p = m.vertices[m.faces[0]]
        n = np.cross(p[1] - p[0], p[2] - p[0])
        return np.sign(n[1])
    assert normal(f'Shape "trianglemesh" {quad}\n') == 1
    assert normal(f'ReverseOrientation\nShape "trianglemesh" {quad}\n') == -1
    assert normal(f'Shape "trianglemesh" {quad} {down}\n') == -1
    assert normal(f'ReverseOrientation\nShape "trianglemesh" {quad} {down}\n') == 1


def test_texture_coordinates_are_flipped_as_pbrt_looks_images_up(tmp_path):
    m = scene(tmp_path, 'Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 1 0 ] "point2 uv" [ 0 0  1 0  0 0.25 ]\n').meshes[0]
    assert np.allclose(m.uvs, [[0, 1], [1, 1], [0, 0.75]])


def test_instances_are_placed_by_their_transforms(tmp_path):
    """An object keeps the transform current at its shapes, each instance adds its own; the
    copies that flattening makes are where pbrt puts them."""
    s = scene(tmp_path, 'ObjectBegin "tri"\nTranslate 0 1 0\nShape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 1 0 ]\n'
                        'Shape "sphere" "float radius" 0.5\nObjectEnd\n'
                        'AttributeBegin\nTranslate 10 0 0\nObjectInstance "tri"\nAttributeEnd\n'
                        'AttributeBegin\nTranslate 0 0 -4\nScale 2 2 2\nObjectInstance "tri"\nAttributeEnd\n')
    assert len(s.instances) == 2 and not s.meshes
    np.testing.assert_allclose(s.instances.objects[0].meshes[0].vertices, [[0, 1, 0], [1, 1, 0], [0, 2, 0]])
    np.testing.assert_allclose(s.instances.to_world[1], translation((0, 0, -4)) @ scaling(2))
    flat = flattened_meshes(s.instances)
    np.testing.assert_allclose(flat[0].vertices, [[10, 1, 0], [11, 1, 0], [10, 2, 0]])
    np.testing.assert_allclose(flat[1].vertices, [[0, 2, -4], [2, 2, -4], [0, 4, -4]])
    # the object's sphere, copied into the world at each instance
    np.testing.assert_allclose(s.spheres, [[10, 1, 0, 0.5], [0, 2, -4, 1.0]])


def test_include_is_relative_to_the_main_file(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "floor.pbrt").write_text(FLOOR)
    (tmp_path / "parts" / "more.pbrt").write_text('Include "parts/floor.pbrt"\n')
    s = scene(tmp_path, 'Include "parts/more.pbrt"\nImport "parts/floor.pbrt"\n')
    assert len(s.meshes) == 2


def test_lights_as_pbrt_places_and_scales_them(tmp_path):
    s = scene(tmp_path, 'LightSource "point" "point3 from" [ 0 2 0 ] "rgb I" [ 1 2 3 ] "float scale" 2\n'
                        'AttributeBegin\nTranslate 0 5 0\n'
                        'LightSource "spot" "point3 from" [ 0 0 0 ] "point3 to" [ 0 -1 0 ] "float coneangle" 40 '
                        '"float conedeltaangle" 10\nAttributeEnd\n'
                        'LightSource "distant" "point3 from" [ 0 1 0 ] "point3 to" [ 0 0 0 ] "blackbody L" 5000 '
                        '"float illuminance" 3\n' + FLOOR)
    point, spot, sun = s.lights
    assert np.allclose(point.position, [0, 2, 0]) and np.allclose(point.intensity, [2, 4, 6])
    assert np.allclose(spot.position, [0, 5, 0]) and np.allclose(spot.direction, [0, -1, 0])
    assert (spot.cutoff_angle, spot.beam_width, spot.falloff) == (40, 30, "smoothstep")
    assert np.allclose(sun.direction, [0, -1, 0])
    y = 0.2126 * sun.irradiance[0] + 0.7152 * sun.irradiance[1] + 0.0722 * sun.irradiance[2]
    assert y == pytest.approx(3.0, rel=0.01)


def test_the_equal_area_square_is_pbrts_layout_and_equal_area():
    d = np.array([[0, 0, 1.0], [1.0, 0, 0], [0, 1.0, 0], [0, 0, -1.0]])
    assert np.allclose(sphere_to_square(d)[:3], [[0.5, 0.5], [1, 0.5], [0.5, 1]])
    assert np.allclose(np.abs(sphere_to_square(d)[3] - 0.5), 0.5)          # -z at the corners
    rng = np.random.default_rng(1)
    v = rng.normal(size=(200_000, 3))
    uv = sphere_to_square(v / np.linalg.norm(v, axis=1, keepdims=True))
    counts, _, _ = np.histogram2d(uv[:, 0], uv[:, 1], bins=10, range=[[0, 1], [0, 1]])
    expected = len(v) / 100
    chi2 = ((counts - expected) ** 2 / expected).sum()
    assert chi2 < 150          # 99 degrees of freedom: p < 1e-3 beyond 148


def test_an_equal_area_map_is_resampled_through_the_lights_transform(tmp_path):
    """A map bright only around light-space +z, turned by Rotate -90 about x, is bright at the
    lat-long map's top (+y)."""
    from pathtrace.io.images import _write_exr
    n = 32
    square = np.zeros((n, n, 3), np.float32)
    square[n // 2 - 2:n // 2 + 2, n // 2 - 2:n // 2 + 2] = 100.0
    _write_exr(str(tmp_path / "sky.exr"), square)
    s = scene(tmp_path, 'AttributeBegin\nRotate -90 1 0 0\nLightSource "infinite" "string filename" "sky.exr"\n'
                        'AttributeEnd\n' + FLOOR)
    env = s.environment.image
    h = env.shape[0]
    assert env.shape == (h, 2 * h, 3) and h % n == 0
    rows = env.mean(axis=(1, 2))
    assert rows[0] > 10 and rows[h // 2:].max() == 0


def test_pixel_filters_are_read_by_their_declared_names(tmp_path, capsys):
    """xradius and yradius are one radius, their mean, with a warning where they differ; a
    filter of negative lobes is pbrt-v4's default gaussian, its radii left unread (they do not
    say the gaussian's)."""
    from pathtrace.filters import PixelFilter
    assert scene(tmp_path, FLOOR, 'PixelFilter "triangle" "float xradius" 1 "float yradius" 2').settings.filter == \
        PixelFilter("tent", 1.5)
    assert "one radius; it uses 1.5" in capsys.readouterr().err
    assert scene(tmp_path, FLOOR, 'PixelFilter "mitchell" "float xradius" 1 "float yradius" 3').settings.filter == \
        PixelFilter("gaussian", 1.5, 0.5) == scene(tmp_path, FLOOR).settings.filter
    err = capsys.readouterr().err
    assert "no mitchell filter" in err and "one radius" not in err


def test_a_stratified_sampler_takes_xsamples_times_ysamples(tmp_path):
    assert scene(tmp_path, FLOOR, 'Sampler "stratified" "integer xsamples" 2 "integer ysamples" 3').settings.spp == 6
    assert scene(tmp_path, FLOOR, 'Sampler "stratified"').settings.spp == 16
    assert scene(tmp_path, FLOOR, 'Sampler "halton" "integer pixelsamples" 8').settings.spp == 8
    assert "s.pbrt:1: 'ysamples': must be in 1.." in fails(tmp_path, 'Sampler "stratified" "integer ysamples" 0\n')


def test_convert_writes_a_pbrt_scene_as_toml_that_reads_the_same(tmp_path):
    from pathtrace.scene.toml_writer import scene_toml
    s = load_scene(str(SCENES / "cbox.pbrt"))
    out = tmp_path / "cbox.toml"
    out.write_text(scene_toml(s, out))
    t = load_scene(str(out))
    assert t.camera.mirrored == s.camera.mirrored and t.triangle_count == s.triangle_count
    assert all(np.allclose(a, b) for a, b in zip(t.camera.basis(1.0), s.camera.basis(1.0)))



def test_a_redefined_named_material_lends_its_name_to_no_other(tmp_path):
    """A name's material redefined fifty times, then anonymous materials: none of their rows is
    named after it (an id of a freed Material, taken by a new one, carried the old one's name)."""
    text = 'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\nLightSource "point" "rgb I" [ 5 5 5 ]\n'
    for k in range(50):
        text += (f'MakeNamedMaterial "A" "string type" "diffuse" "rgb reflectance" [ 0.5 0.5 {k / 100} ]\n'
                 'AttributeBegin\nMaterial "conductor"\nShape "sphere" "float radius" 0.1\nAttributeEnd\n')
    (tmp_path / "s.pbrt").write_text(text)
    s = load_scene(str(tmp_path / "s.pbrt"))
    assert "A" not in list(s.materials) and len(s.spheres) == 50

def test_convert_writes_a_key_for_each_material_whatever_the_files_names(tmp_path):
    """A named material called "material0" beside an anonymous row 0 (whose key convert makes up
    as "material0"): each row a key of its own, the file's name kept, and the TOML reads back
    with each shape's material (the second key of a name was invalid TOML)."""
    from pathtrace.scene.toml_writer import scene_toml
    (tmp_path / "s.pbrt").write_text(
        'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\nLightSource "point" "rgb I" [ 5 5 5 ]\n'
        'Material "conductor"\nShape "sphere" "float radius" 1\n'
        'MakeNamedMaterial "material0" "string type" "diffuse" "rgb reflectance" [ 0.1 0.8 0.1 ]\n'
        'NamedMaterial "material0"\nTranslate 2.5 0 0\nShape "sphere" "float radius" 1\n')
    s = load_scene(str(tmp_path / "s.pbrt"))
    out = tmp_path / "s.toml"
    out.write_text(scene_toml(s, out))
    t = load_scene(str(out))
    assert [t.materials[int(r)].type for r in t.sphere_material] == ["conductor", "diffuse"]
    assert t.materials["material0"].type == "diffuse"

# -- bad input: one line naming the file and line --

@pytest.mark.parametrize("text,expected", [
    ('WorldBegin\nShape "trianglemesh" "point3 P" [ 0 0 0  1 0 0', "unterminated '['"),
    # pbrt-v4's blocks (src/pbrt/scene.cpp: VERIFY_OPTIONS, VERIFY_WORLD, EndOfFiles)
    ('Shape "sphere"\nWorldBegin\n', 's.pbrt:1: the scene description must be inside the world block; "Shape"'),
    ('WorldBegin\nCamera "perspective"\n', 's.pbrt:2: options cannot be set inside the world block; "Camera"'),
    ('WorldBegin\nWorldBegin\n', 's.pbrt:2: options cannot be set inside the world block; "WorldBegin"'),
    ('Camera "perspective"\n', "the file ends before WorldBegin"),
    ('WorldBegin\nAttributeBegin\nShape "sphere"\n', "s.pbrt:2: AttributeBegin without its end, as the file ends"),
    ('WorldBegin\nObjectBegin "o"\nAttributeBegin\nObjectEnd\n',
     "s.pbrt:4: ObjectEnd without ObjectBegin (the block open is the AttributeBegin of "),
    ('TransformBegin\nWorldBegin\n', 's.pbrt:1: the scene description must be inside the world block; "TransformBegin"'),
    ('WorldBegin\nShape "trianglemesh\n', "s.pbrt:2: an unterminated string"),
    ('WorldBegin\nMaterial "diffuse" "spectrum reflectance" [ "metal-Cu-eta"\nShape "sphere" "float radius" [ 1 ]\n',
     "s.pbrt:2: 'reflectance': its '[' is not closed by a ']' before a list of numbers at line 3"),
    ('WorldBegin\nFrobnicate 1 2 3\n', "s.pbrt:2: unknown directive 'Frobnicate'"),
    ('Camera "perspective" "float fov" [ "wide" ]\nWorldBegin\n', "float values must be numbers"),
    ('LookAt 0 0 0  0 0 1  0 1\nWorldBegin\n', "expected a number"),
    ('Camera "perspective" "float fov" [ 1e40 ]\nWorldBegin\n', "beyond what float32 holds"),
    ('Camera "perspective" "point3 fov" [ 1 2 ]\nWorldBegin\n', "groups of 3"),
    ('WorldBegin\nShape "sphere" "integer radius" [ 1.5 ]\n', "whole numbers"),
    ('WorldBegin\nShape "sphere" "float radius" [ 1 2 ]\n', "takes 1 value"),
    ('WorldBegin\nShape "sphere" "float radius" -1\n', "sphere's radius must be positive"),
    ('WorldBegin\nAttributeEnd\n', "AttributeEnd without AttributeBegin"),
    ('WorldBegin\nNamedMaterial "nothing"\n', "no material named 'nothing'"),
    ('WorldBegin\nLightSource "spot" "float coneangle" 200\n' + FLOOR, "s.pbrt:2: 'coneangle': must be in (0, 180]"),
    ('WorldBegin\nLightSource "point" "rgb I" [ -1 1 1 ]\n' + FLOOR, "'I'"),
    ('WorldBegin\nLightSource "distant" "point3 to" [ 0 0 0 ]\n' + FLOOR, "'to'"),
    ('Camera "perspective" "float lensradius" -1\nWorldBegin\n' + FLOOR, "s.pbrt:1: 'lensradius': must be in [0, "),
    # the thin lens's range, under pbrt-v4's name
    ('Camera "perspective" "float lensradius" 1 "float focaldistance" 0\nWorldBegin\n' + FLOOR,
     "s.pbrt:1: 'focaldistance': must be in (0, "),
    ('Camera "perspective" "float fov" 180\nWorldBegin\n' + FLOOR, "s.pbrt:1: 'fov': must lie in (0, 180) degrees"),
    ('Camera "orthographic" "float frameaspectratio" -2\nWorldBegin\n' + FLOOR,
     "s.pbrt:1: 'frameaspectratio': must be positive, got -2"),
    ('Camera "perspective" "float screenwindow" [ -1 1 -1 ]\nWorldBegin\n' + FLOOR,
     "s.pbrt:1: 'screenwindow': takes x0 x1 y0 y1"),
    ('PixelFilter "gaussian" "float xradius" 0 "float yradius" 0\nWorldBegin\n', "s.pbrt:1: 'xradius' and 'yradius': "),
    ('PixelFilter "gaussian" "float sigma" 0\nWorldBegin\n', "s.pbrt:1: 'sigma': must be in"),
    ('WorldBegin\n' + FLOOR.replace("0 3 2", "0 3 9"), "refers to vertex"),
])
def test_bad_input_is_one_line_naming_the_file(tmp_path, text, expected):
    message = fails(tmp_path, text)
    assert "s.pbrt" in message and expected in message, message


def test_transform_begin_and_end_save_and_restore_the_whole_state_as_pbrt_v4s_parser_takes_them(tmp_path, capsys):
    """pbrt-v4's parser takes TransformBegin/End as AttributeBegin/End (src/pbrt/parser.cpp): the
    material set inside is undone at the end, where pathtrace restored the transform alone."""
    s = scene(tmp_path, 'TransformBegin\nTranslate 5 0 0\nMaterial "conductor"\nTransformEnd\nShape "sphere"\n')
    assert s.materials.get(int(s.sphere_material[0])).type == "diffuse" and np.allclose(s.spheres[0, :3], 0)
    assert "TransformBegin/End are deprecated in pbrt-v4" in capsys.readouterr().err


@pytest.mark.parametrize("text,expected", [
    # pbrt-v4 looks a parameter up by its name and its type as written (src/pbrt/paramdict.cpp,
    # lookupSingle and lookupArray): another type is never read, and ReportUnused refuses the file
    ('WorldBegin\nShape "sphere" "integer radius" 2\n',
     's.pbrt:2: \'radius\': pbrt-v4 reads a float here and refuses an integer ("radius": unused parameter); '
     'write "float radius"'),
    ('Camera "perspective" "integer fov" 45\nWorldBegin\n' + FLOOR, "s.pbrt:1: 'fov': pbrt-v4 reads a float here"),
    ('WorldBegin\nLightSource "point" "vector3 from" [ 0 1 0 ]\n' + FLOOR, "s.pbrt:2: 'from': must be point3, got vector3"),
    ('Film "rgb" "float pixelbounds" [ 0 1 0 1 ]\nWorldBegin\n' + FLOOR, "s.pbrt:1: 'pixelbounds': must be integer"),
    # pbrt-v3's type names: pbrt-v4 knows them only when --upgrade rewrites the file
    # (ParameterDictionary::checkParameterTypes: "unknown parameter type")
    ('WorldBegin\nMaterial "diffuse" "color reflectance" [ 0.5 0.5 0.5 ]\n' + FLOOR,
     's.pbrt:2: "color reflectance": color is pbrt-v3\'s parameter type, which pbrt-v4 refuses; '
     'write "rgb reflectance"'),
    ('WorldBegin\nShape "trianglemesh" "point P" [ 0 0 0 1 0 0 0 1 0 ]\n', "s.pbrt:2: \"point P\": point is pbrt-v3's"),
    ('WorldBegin\nLightSource "distant" "vector to" [ 0 0 1 ]\n' + FLOOR, "vector is pbrt-v3's"),
    ('WorldBegin\nShape "trianglemesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 ] "float uv" [ 0 0 1 0 0 1 ]\n',
     "s.pbrt:2: 'uv': must be point2, got float"),
    # what pbrt-v4 reads and pathtrace does not is read as pbrt-v4 reads it (a type's `unsupported`)
    ('Film "rgb" "float filename" 3\nWorldBegin\n' + FLOOR, "s.pbrt:1: 'filename': must be string, got float"),
    ('Film "rgb" "string filename" [ "a.exr" "b.exr" ]\nWorldBegin\n' + FLOOR, "s.pbrt:1: 'filename': takes 1 value, got 2"),
    ('WorldBegin\nShape "loopsubdiv" "string levels" "x" "point3 P" [ 0 0 0 1 0 0 0 1 0 ] "integer indices" [ 0 1 2 ]\n',
     "s.pbrt:2: 'levels': must be integer, got string"),
    ('WorldBegin\nMakeNamedMedium "m" "string type" "homogeneous" "float preset" 1\n' + FLOOR,
     "s.pbrt:2: 'preset': must be string, got float"),
    ('WorldBegin\nShape "plymesh"\n', 's.pbrt:2: Shape "plymesh": needs a filename'),
    # a coated conductor's metal is pbrt-v4's conductor.eta, not a conductor's eta
    ('WorldBegin\nMaterial "coatedconductor" "rgb conductor.eta" [ 200 1 1 ]\n' + FLOOR,
     "s.pbrt:2: the coatedconductor material's eta (from 'conductor.eta') must lie in [0, 100]"),
    # a type pbrt-v4 has not either ('%s: shape type unknown.' and the like: known_parameters.json's types)
    ('WorldBegin\nShape "plymseh" "string filename" "x.ply"\n' + FLOOR,
     "s.pbrt:2: pbrt-v4 has no shape type 'plymseh', and refuses it; did you mean 'plymesh'?"),
    ('WorldBegin\nMaterial "difuse"\n' + FLOOR, "s.pbrt:2: pbrt-v4 has no material type 'difuse', and refuses it; "
                                                "did you mean 'diffuse'?"),
    ('WorldBegin\nLightSource "pont"\n' + FLOOR, "s.pbrt:2: pbrt-v4 has no light type 'pont'"),
    ('Integrator "bdtp"\nWorldBegin\n' + FLOOR, "s.pbrt:1: pbrt-v4 has no integrator type 'bdtp', and refuses it; "
                                                 "did you mean 'bdpt'?"),
    ('Camera "perspectve"\nWorldBegin\n' + FLOOR, "s.pbrt:1: pbrt-v4 has no camera type 'perspectve'"),
    ('Film "rbg"\nWorldBegin\n' + FLOOR, "s.pbrt:1: pbrt-v4 has no film type 'rbg'"),
    # each integrator's own parameters, as pbrt-v4's Create() reads them
    ('Integrator "bdpt" "integer maxdepht" 5\nWorldBegin\n' + FLOOR,
     "s.pbrt:1: 'maxdepht' is not a parameter of pbrt-v4's bdpt integrator, which pbrt-v4 refuses; "
     "did you mean 'maxdepth'?"),
    ('Integrator "sppm" "float raduis" 0.1\nWorldBegin\n' + FLOOR,
     "s.pbrt:1: 'raduis' is not a parameter of pbrt-v4's sppm integrator"),
    ('Integrator "mlt" "string lightsampler" "power"\nWorldBegin\n' + FLOOR,
     "s.pbrt:1: 'lightsampler' is not a parameter of pbrt-v4's mlt integrator"),
    ('Integrator "lightpath" "string lightsampler" "bvh"\nWorldBegin\n' + FLOOR,
     "s.pbrt:1: 'lightsampler' is not a parameter of pbrt-v4's lightpath integrator"),
])
def test_a_file_pbrt_v4_refuses_is_one_line_naming_the_line(tmp_path, text, expected):
    message = fails(tmp_path, text)
    assert expected in message and "\n" not in message.strip(), message


def test_an_include_cycle_and_a_fifo_are_refused(tmp_path):
    (tmp_path / "a.pbrt").write_text('Include "b.pbrt"\n')
    (tmp_path / "b.pbrt").write_text('Include "a.pbrt"\n')
    assert "includes itself" in fails(tmp_path, 'WorldBegin\nInclude "a.pbrt"\n')
    os.mkfifo(tmp_path / "fifo.pbrt")
    assert "fifo.pbrt" in fails(tmp_path, 'WorldBegin\nInclude "fifo.pbrt"\n', "t.pbrt")


def test_a_ply_gz_that_is_not_gzip_and_a_huge_vertex_claim_are_refused(tmp_path):
    (tmp_path / "bad.ply.gz").write_bytes(b"ply\nformat ascii 1.0\nend_header\n")
    assert "bad.ply.gz" in fails(tmp_path, 'WorldBegin\nShape "plymesh" "string filename" "bad.ply.gz"\n')
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 1099511627776\nproperty float x\n"
              b"property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
              b"end_header\n")
    (tmp_path / "huge.ply.gz").write_bytes(gzip.compress(header + b"\0" * 64))
    assert "huge.ply.gz" in fails(tmp_path, 'WorldBegin\nShape "plymesh" "string filename" "huge.ply.gz"\n')


def test_convert_writes_turned_meshes_and_resampled_maps_beside_the_toml(tmp_path):
    """A mesh with normals (which TOML cannot hold inline) and the lat-long form of an
    equal-area map go to files beside the TOML; the converted scene reads the same."""
    from pathtrace.io.images import _write_exr
    _write_exr(str(tmp_path / "sky.exr"), np.full((8, 8, 3), 0.5, np.float32))
    (tmp_path / "s.pbrt").write_text(
        'LookAt 0 2 5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\n'
        'LightSource "infinite" "string filename" "sky.exr"\n'
        'Shape "trianglemesh" "point3 P" [ -1 0 -1  1 0 -1  1 0 1  -1 0 1 ] "integer indices" [ 0 2 1  0 3 2 ]'
        ' "normal N" [ 0 -1 0  0 -1 0  0 -1 0  0 -1 0 ] "point2 uv" [ 0 0  1 0  1 1  0 1 ]\n')
    r = in_process("convert", tmp_path / "s.pbrt", "-o", tmp_path / "out.toml")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "out.environment.exr").is_file() and list((tmp_path / "out.meshes").glob("*.ply"))
    assert f"wrote 1 mesh to {tmp_path / 'out.meshes'}/" in r.stderr      # where they are, not only their name
    a, b = load_scene(str(tmp_path / "s.pbrt")), load_scene(str(tmp_path / "out.toml"))
    assert b.camera.mirrored and np.allclose(a.environment.image, b.environment.image)
    for name in ("vertices", "faces", "normals", "uvs"):
        assert np.allclose(getattr(a.meshes[0], name), getattr(b.meshes[0], name)), name


def test_convert_writes_an_inverted_imagemaps_texels_beside_the_toml(tmp_path):
    """pbrt-v4's `invert` is baked into the texels as the file is read: convert once wrote the
    original file's name, and the converted scene rendered the map uninverted (a new user's
    run, 2026-12-03: mean 0.075 against 0.225). The texels go to an EXR file beside the TOML."""
    from PIL import Image as PILImage      # with an alpha channel, which no texture reads: its rgb written
    PILImage.open(Path(__file__).parent / "scenes" / "textures" / "tiles.png").convert("RGBA").save(tmp_path / "tiles.png")
    (tmp_path / "s.pbrt").write_text(
        'LookAt 0 2 5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\n'
        'Texture "t" "spectrum" "imagemap" "string filename" "tiles.png" "bool invert" true "float scale" 0.8\n'
        'Material "diffuse" "texture reflectance" "t"\n' + FLOOR)
    r = in_process("convert", tmp_path / "s.pbrt", "-o", tmp_path / "out.toml")
    assert r.returncode == 0 and f"wrote {tmp_path / 'out.image0.exr'}" in r.stderr, r.stderr
    a, b = (load_scene(str(tmp_path / n)).materials.get(0).params["rho_d"] for n in ("s.pbrt", "out.toml"))
    image_a, image_b = (t.params["image"] if t.type == "bitmap" else t.params["tex"].params["image"] for t in (a, b))
    assert image_b.path.endswith("out.image0.exr")
    np.testing.assert_allclose(image_b.rgb(), image_a.rgb(), rtol=1e-6)


def test_coateddiffuse_is_pbrts_layered_material(tmp_path):
    """pbrt-v4's coateddiffuse keeps its parameters (roughness remapped by default, maxdepth,
    nsamples, the layer's thickness, albedo and g); a roughness below pbrt's 1e-3 is smooth."""
    s = scene(tmp_path, 'Material "coateddiffuse" "rgb reflectance" [0.2 0.4 0.6] "float roughness" 0.04 '
                        '"float thickness" 0.2 "rgb albedo" [0.5 0.5 0.5] "float g" 0.3 "integer maxdepth" 20 '
                        '"integer nsamples" 2 "float eta" 1.4\n' + FLOOR
              + 'Material "coateddiffuse" "float roughness" 0.0005 "bool remaproughness" false\n' + FLOOR)
    rough, smooth = (s.materials.get(m.material) for m in s.meshes)
    assert rough.type == smooth.type == "coateddiffuse" and rough.twosided
    np.testing.assert_allclose(rough.params["reflectance"], [0.2, 0.4, 0.6])
    assert rough.params["alpha"] == pytest.approx(0.2)            # sqrt(0.04)
    assert (rough.params["thickness"], rough.params["g"], rough.params["maxdepth"], rough.params["nsamples"],
            rough.params["eta"]) == pytest.approx((0.2, 0.3, 20, 2, 1.4))
    np.testing.assert_allclose(rough.params["albedo"], 0.5)
    assert (smooth.params["alpha"], smooth.params["maxdepth"], smooth.params["thickness"]) == pytest.approx((0, 10, 0.01))


def test_coatedconductor_is_pbrts_layered_material(tmp_path):
    """pbrt-v4's coatedconductor: its coating's and metal's roughness (prefixed interface. and
    conductor., u and v apart), the coating's eta, the layer; copper by default, or a
    reflectance; all-smooth with a clear layer it is a delta BSDF."""
    from pathtrace.materials.optics import CONDUCTORS
    s = scene(tmp_path, 'Material "coatedconductor" "float interface.roughness" 0.01 "float conductor.uroughness" 0.09 '
                        '"float conductor.vroughness" 0.04 "float interface.eta" 1.33 "float thickness" 0.1 '
                        '"rgb albedo" [0.2 0.3 0.4] "integer maxdepth" 15\n' + FLOOR
              + 'Material "coatedconductor" "rgb reflectance" [0.9 0.5 0.2]\n' + FLOOR)
    rough, smooth = (s.materials.get(m.material) for m in s.meshes)
    assert rough.type == smooth.type == "coatedconductor" and rough.twosided
    assert (rough.params["alpha"], rough.params["alpha_v"], rough.params["conductor_alpha"],
            rough.params["conductor_alpha_v"]) == pytest.approx((0.1, 0.1, 0.3, 0.2))
    assert (rough.params["interface_eta"], rough.params["thickness"], rough.params["maxdepth"]) == pytest.approx((1.33, 0.1, 15))
    np.testing.assert_allclose(rough.params["eta"], CONDUCTORS["Cu"][0], rtol=0.05)   # pbrt's copper, as RGB
    assert smooth.params["alpha"] == smooth.params["conductor_alpha"] == 0
    assert s.materials.rows[s.meshes[1].material]["flags"] & 2      # MATERIAL_DELTA
    assert "'nsamples': must lie in [1, 16], got 100" in fails(
        tmp_path, 'WorldBegin\nMaterial "coatedconductor" "integer nsamples" 100\n' + FLOOR)


def test_unnamed_analytic_shapes_are_numbered_by_kind(tmp_path):
    """Each reader's unnamed sphere, disk, ... is "<kind> N", counted by kind whichever range it
    lands in: whole spheres go to the sphere range, where every one had been named "sphere 0"
    (a helper's run of `convert`). The Mitsuba reader names them alike."""
    (tmp_path / "s.pbrt").write_text(
        'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\nLightSource "point" "rgb I" [ 1 1 1 ]\n'
        'Shape "sphere" "float radius" 1\nTranslate 3 0 0\nShape "sphere" "float radius" 1\n'
        'Shape "disk" "float radius" 1\nShape "disk" "float radius" 2\n')
    s = load_scene(str(tmp_path / "s.pbrt"))
    assert list(s.sphere_names) == ["sphere 0", "sphere 1"] and [x.name for x in s.shapes] == ["disk 0", "disk 1"]
    blend = load_scene(str(Path(__file__).parent / "scenes" / "blend.xml"))
    assert list(blend.sphere_names) == [f"sphere {k}" for k in range(len(blend.spheres))]


def test_named_materials_name_their_rows(tmp_path):
    """A MakeNamedMaterial's name names its row of the scene's materials, as a Mitsuba bsdf's id
    and a TOML table's key do (the viewer's pick showed "material #4" for the file's "Wood");
    an anonymous Material's row has none, and a named one given an emission is a row of its own."""
    (tmp_path / "s.pbrt").write_text(
        'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\n'
        'MakeNamedMaterial "Wood" "string type" "diffuse" "rgb reflectance" [ 0.5 0.3 0.1 ]\n'
        'NamedMaterial "Wood"\nShape "sphere" "float radius" 1\nTranslate 3 0 0\nShape "sphere" "float radius" 1\n'
        'Material "conductor"\nShape "sphere" "float radius" 0.5\n'
        'NamedMaterial "Wood"\nAreaLightSource "diffuse" "rgb L" [ 1 1 1 ]\nShape "sphere" "float radius" 0.2\n')
    s = load_scene(str(tmp_path / "s.pbrt"))
    wood = s.materials["Wood"]
    assert wood.type == "diffuse" and np.allclose(wood.params["rho_d"], [0.5, 0.3, 0.1])
    rows = list(s.sphere_material)
    assert rows[0] == rows[1] == list(s.materials).index("Wood") and len(set(rows)) == 3


def test_reflectances_beyond_0_and_1_are_clamped_as_pbrt_clamps_them(tmp_path):
    """pbrt-v4's diffuse, coateddiffuse and diffusetransmission materials clamp their
    reflectances into [0, 1] where they evaluate them (DiffuseMaterial::GetBxDF's Clamp, as
    CoatedDiffuse's reflectance and albedo, DiffuseTransmission's scale times each), so a file
    that gives 1.2 renders in pbrt-v4, as 1: a constant is clamped as it is read. Diffuse
    transmission's two are clamped each, and may sum above 1, as pbrt-v4 renders them."""
    s = scene(tmp_path, 'Material "diffuse" "rgb reflectance" [1.2 0.5 -0.1]\n' + FLOOR
              + 'Material "coateddiffuse" "rgb reflectance" [1.5 0.2 0.2] "rgb albedo" [2 0.5 0.5] '
                '"float thickness" 0.1\n' + FLOOR
              + 'Material "diffusetransmission" "rgb reflectance" [0.6 0.2 0.1] "rgb transmittance" [0.7 0 0] '
                '"float scale" 2\n' + FLOOR)
    diffuse, coated, transmitting = (s.materials.get(m.material) for m in s.meshes)
    np.testing.assert_allclose(diffuse.params["rho_d"], [1, 0.5, 0])
    np.testing.assert_allclose(coated.params["reflectance"], [1, 0.2, 0.2])
    np.testing.assert_allclose(coated.params["albedo"], [1, 0.5, 0.5])
    np.testing.assert_allclose(transmitting.params["reflectance"], [1, 0.4, 0.2])
    # each clamped, not their sum: 1 + 1 in the red, which pbrt-v4 renders as it is
    np.testing.assert_allclose(transmitting.params["transmittance"], [1, 0, 0])
