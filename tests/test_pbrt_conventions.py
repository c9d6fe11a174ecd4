"""pbrt-v4's conventions at the reader's boundary (issue 57), each as pbrt-v4's source has it:
what the reader makes of a file, and where it shows, a small render's statistic."""

import math

import numpy as np
import pytest

from pathtrace.rendering.renderer import Renderer
from tests.test_pbrt import FLOOR, scene

LIGHT_QUAD = '"point3 P" [ -0.5 1.5 -0.5  0.5 1.5 -0.5  0.5 1.5 0.5  -0.5 1.5 0.5 ] "integer indices" [ 0 1 2  0 2 3 ]'


def emissions(s):
    """The emitted radiance of each material row that the meshes emit by."""
    rows = sorted({m.material for m in s.meshes})
    return [e for e in (s.materials.get(r).emission for r in rows) if e is not None and np.any(e > 0)]


# -- lights --

def test_spot_lights_read_conedeltaangle(tmp_path):
    """pbrt-v4 SpotLight::Create: GetOneFloat("conedeltaangle", 5.); the beam is coneangle minus it."""
    s = scene(tmp_path, 'LightSource "spot" "point3 from" [ 0 2 0 ] "point3 to" [ 0 0 0 ] "float coneangle" 40 '
                        '"float conedeltaangle" 20\n' + FLOOR)
    assert (s.lights[0].cutoff_angle, s.lights[0].beam_width) == (40, 20)
    default = scene(tmp_path, 'LightSource "spot" "float coneangle" 40\n' + FLOOR)
    assert default.lights[0].beam_width == 35


def test_area_power_is_per_triangle_and_keeps_ls_magnitude(tmp_path):
    """pbrt-v4 makes one DiffuseAreaLight per triangle, each scaled by power / (pi area), its
    own area; an RGB L is not divided by its luminance."""
    s = scene(tmp_path, 'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [ 1 0.9 0.8 ] "float power" 20\n'
                        f'Shape "trianglemesh" {LIGHT_QUAD}\nAttributeEnd\n' + FLOOR)
    (le,) = emissions(s)           # the quad's two triangles, of area 1/2 each, share a row
    assert np.allclose(le, np.array([1, 0.9, 0.8]) * 20 / (math.pi * 0.5), rtol=1e-6)
    # a triangle of area 2 and one of area 1/2, two-sided: a radiance each
    s = scene(tmp_path, 'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [ 1 1 1 ] "float power" 10 "bool twosided" true\n'
                        'Shape "trianglemesh" "point3 P" [ 0 1 0  2 1 0  0 1 2  5 1 5  6 1 5  5 1 6 ] '
                        '"integer indices" [ 0 1 2  3 4 5 ]\nAttributeEnd\n' + FLOOR)
    got = sorted(float(e[0]) for e in emissions(s))
    assert got == pytest.approx(sorted(10 / (2 * math.pi * a) for a in (2.0, 0.5)), rel=1e-6)
    sphere = scene(tmp_path, 'AttributeBegin\nAreaLightSource "diffuse" "float power" 10\n'
                             'Shape "sphere" "float radius" 0.5\nAttributeEnd\n' + FLOOR)
    row = int(sphere.sphere_material[0])
    assert sphere.materials.get(row).emission == pytest.approx(np.full(3, 10 / (math.pi * 4 * math.pi * 0.25)))


# -- textures --

def test_invert_on_a_colour_imagemap_inverts_each_channel(tmp_path):
    """pbrt-v4 SpectrumImageTexture::Evaluate: ClampZero(1 - scale * rgb), per channel."""
    from PIL import Image
    Image.fromarray(np.array([[[255, 0, 0], [0, 0, 255]]], np.uint8)).save(tmp_path / "rb.png")
    s = scene(tmp_path, 'Texture "t" "spectrum" "imagemap" "string filename" "rb.png" "bool invert" true\n'
                        'Material "diffuse" "texture reflectance" "t"\n' + FLOOR)
    texture = s.materials.get(s.meshes[0].material).params["rho_d"]
    assert texture.type == "bitmap"
    assert np.allclose(texture.params["image"].rgb()[0], [[0, 1, 1], [1, 1, 0]])
    assert np.allclose(texture.mean(), [0.5, 1, 0.5])
    s = scene(tmp_path, 'Texture "t" "spectrum" "imagemap" "string filename" "rb.png" "bool invert" true '
                        '"float scale" 2 "string encoding" "linear"\nMaterial "diffuse" "texture reflectance" "t"\n' + FLOOR)
    # 1 - 2 * 1 clamps at zero, as pbrt's ClampZero does
    assert np.allclose(s.materials.get(s.meshes[0].material).params["rho_d"].mean(), [0.5, 1, 0.5])


# -- the camera --

@pytest.mark.parametrize("camera,film,half_height", [
    ('"float screenwindow" [ -1.5 1.5 -0.75 0.75 ]', (80, 40), 0.75),
    ('"float frameaspectratio" 0.5', (40, 80), 2.0),
    ('', (40, 80), 2.0),
    ('', (80, 40), 1.0)])
def test_screenwindow_and_frameaspectratio_frame_the_image_as_pbrt(tmp_path, camera, film, half_height):
    """pbrt-v4's screen window: [-frame, frame] x [-1, 1] for frame > 1, else [-1, 1] x
    [-1/frame, 1/frame], or the file's screenwindow; tan(fov / 2) per unit of it."""
    s = scene(tmp_path, FLOOR, f'Camera "perspective" "float fov" 30 {camera}\n'
                               f'Film "rgb" "integer xresolution" {film[0]} "integer yresolution" {film[1]}\n')
    assert math.tan(math.radians(s.camera.vfov) / 2) == pytest.approx(math.tan(math.radians(15)) * half_height)


def test_a_screenwindow_off_centre_or_of_another_aspect_warns_what_is_used(tmp_path, capsys):
    scene(tmp_path, FLOOR, 'Camera "perspective" "float screenwindow" [ 0 2 -1 1 ]\n'
                           'Film "rgb" "integer xresolution" 40 "integer yresolution" 40\n')
    err = capsys.readouterr().err
    assert "centred window of the same size, [-1 1 -1 1]" in err
    scene(tmp_path, FLOOR, 'Camera "perspective" "float screenwindow" [ -2 2 -1 1 ]\n'
                           'Film "rgb" "integer xresolution" 40 "integer yresolution" 40\n')
    assert "pixels that are not square" in capsys.readouterr().err


# -- shapes --

def ascii_ply(path, vertices, faces):
    path.write_text("ply\nformat ascii 1.0\n" f"element vertex {len(vertices)}\nproperty float x\nproperty float y\n"
                    f"property float z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
                    + "".join(" ".join(map(str, v)) + "\n" for v in vertices)
                    + "".join(f"3 {' '.join(map(str, f))}\n" for f in faces))


def test_degenerate_triangles_are_dropped_with_one_warning_that_counts_them(tmp_path, capsys):
    """pbrt-v4's IntersectTriangle never hits a triangle of zero area: such triangles are
    dropped, counted in one warning; a mesh left with none is left out, with a warning."""
    ascii_ply(tmp_path / "flat.ply", [(0, 0, 0), (1, 0, 0), (2, 0, 0)], [(0, 1, 2), (0, 0, 1)])
    s = scene(tmp_path, 'Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 0 1  2 0 0 ] '
                        '"integer indices" [ 0 1 2  0 1 3  1 1 2 ]\n'
                        'Shape "plymesh" "string filename" "flat.ply"\n'
                        'Shape "trianglemesh" "point3 P" [ 0 0 0  1 1 1  2 2 2 ] "integer indices" [ 0 1 2 ]\n')
    assert [len(m.faces) for m in s.meshes] == [1]
    err = capsys.readouterr().err.strip().splitlines()
    assert sum("dropped 5 degenerate triangle(s)" in line for line in err) == 1
    assert sum("every triangle of the" in line and "leaves the shape out" in line for line in err) == 2
    assert len(err) == 3


def test_a_scene_of_degenerate_triangles_only_is_its_environment(tmp_path, capsys):
    """Its shape left out (pbrt-v4 never hits it), the scene renders as pbrt-v4 renders one
    without shapes: its environment, black here, with a line for each."""
    s = scene(tmp_path, 'Shape "trianglemesh" "point3 P" [ 0 0 0  1 1 1  2 2 2 ] "integer indices" [ 0 1 2 ]\n')
    assert not s.meshes
    err = capsys.readouterr().err
    assert "leaves the shape out" in err and "the scene has no shapes; pathtrace renders its environment alone" in err


# -- materials' shading maps --

def test_displacement_is_a_bump_map_and_normalmap_a_normal_map(tmp_path, capsys):
    """pbrt-v4's materials take a float texture `displacement` (BumpMap) or a `string
    normalmap` read with a linear encoding (NormalMap): pathtrace's bump and normal maps."""
    from PIL import Image
    Image.fromarray(np.array([[10, 200], [30, 90]], np.uint8)).save(tmp_path / "h.png")
    Image.fromarray(np.array([[[128, 128, 255], [200, 128, 200]]], np.uint8)).save(tmp_path / "n.png")
    s = scene(tmp_path, 'Texture "bump" "float" "imagemap" "string filename" "h.png" "float scale" 0.02\n'
                        'Material "diffuse" "texture displacement" "bump"\n' + FLOOR)
    bump = s.materials.get(s.meshes[0].material).bump_map
    assert bump.type == "scale" and bump.params["tex"].type == "bitmap"
    assert np.allclose(bump.params["scale"], 0.02)
    s = scene(tmp_path, 'MakeNamedMaterial "m" "string type" "conductor" "string normalmap" "n.png"\n'
                        'NamedMaterial "m"\n' + FLOOR)
    normal = s.materials.get(s.meshes[0].material).normal_map
    assert normal.type == "bitmap" and normal.params["image"].linear
    assert (normal.params["wrap"], normal.params["filter"]) == ("repeat", "bilinear")
    assert "not a parameter" not in capsys.readouterr().err
    s = scene(tmp_path, 'Texture "c" "float" "checkerboard"\nMaterial "diffuse" "texture displacement" "c"\n' + FLOOR)
    assert s.materials.get(s.meshes[0].material).bump_map is None
    assert "the surface is rendered unbumped" in capsys.readouterr().err


def test_pbrt_shading_maps_perturb_as_pbrts_and_convert_keeps_it(tmp_path):
    """pbrt-v4's NormalMap and BumpMap leave the normal on the geometric normal's side with no
    shadow-terminator term, Mitsuba 3's mirror it about the normal and weigh by one
    (Material.perturbation; against pbrt-v4's own render: tests/test_pbrt_reference.py, normalmap,
    which was 1.3 % dark with Mitsuba's). The reader says "pbrt" for both maps, and a TOML file
    written by convert keeps it."""
    from PIL import Image
    from pathtrace.scene import load_scene
    from tests.commands import in_process
    Image.fromarray(np.array([[10, 200], [30, 90]], np.uint8)).save(tmp_path / "h.png")
    Image.fromarray(np.array([[[128, 128, 255], [200, 128, 200]]], np.uint8)).save(tmp_path / "n.png")
    s = scene(tmp_path, 'Texture "bump" "float" "imagemap" "string filename" "h.png"\n'
                        'Material "diffuse" "texture displacement" "bump"\n' + FLOOR
              + 'Material "conductor" "string normalmap" "n.png"\nTranslate 0 1 0\n' + FLOOR)
    rows = [s.materials.get(m.material) for m in s.meshes]
    assert [(m.bump_map is not None, m.normal_map is not None, m.perturbation) for m in rows] == \
        [(True, False, "pbrt"), (False, True, "pbrt")]
    r = in_process("convert", tmp_path / "s.pbrt", "-o", tmp_path / "out.toml")
    assert r.returncode == 0, r.stderr
    assert [b.materials.get(m.material).perturbation for b in [load_scene(str(tmp_path / "out.toml"))]
            for m in b.meshes] == ["pbrt", "pbrt"]


def test_textures_nest_as_pbrt_nests_them(tmp_path):
    """A mix of a checkerboard and a colour (tex_mix of tests/references/pbrt-v4), and a
    scale of a scale of a checkerboard of checkerboards: read as the trees they are."""
    s = scene(tmp_path, 'Texture "a" "spectrum" "checkerboard" "float uscale" 4 "float vscale" 4 '
                        '"rgb tex1" [ 0.8 0.8 0.8 ] "rgb tex2" [ 0.1 0.1 0.1 ]\n'
                        'Texture "t" "spectrum" "mix" "texture tex1" "a" "rgb tex2" [ 0.2 0.5 0.2 ] "float amount" 0.3\n'
                        'Texture "b" "spectrum" "checkerboard" "texture tex1" "a" "texture tex2" "t"\n'
                        'Texture "s" "spectrum" "scale" "texture tex" "b" "float scale" 0.5\n'
                        'Texture "ss" "spectrum" "scale" "texture tex" "s" "float scale" 0.5\n'
                        'Material "diffuse" "texture reflectance" "ss"\n' + FLOOR)
    ss = s.materials.get(s.meshes[0].material).params["rho_d"]
    b = ss.params["tex"].params["tex"]
    assert (ss.type, b.type, b.params["color1"].type, b.params["color1"].params["tex1"].type) == \
        ("scale", "checkerboard", "mix", "checkerboard")
    mix_mean = 0.7 * 0.45 + 0.3 * np.array([0.2, 0.5, 0.2])
    assert np.allclose(ss.mean(), 0.25 * (0.45 + mix_mean) / 2)


# -- the equal-area sky --

def test_an_equal_area_sky_takes_pbrts_nearest_texels_unblurred_to_the_squares_edges():
    """pbrt-v4's ImageInfiniteLight::ImageLe looks the square up at the nearest texel: one bright
    texel on the square's edge is, in the lat-long map, its value where its solid angle is (not
    blurred by a second bilinear resampling, nor by a clamp at the edge), and its solid angle is
    the equal-area square's 4 pi / N^2."""
    from pathtrace.scene.pbrt.equal_area import to_latlong
    n = 16
    square = np.zeros((n, n, 3), np.float32)
    square[5, n - 1] = 1000.0
    latlong = to_latlong(square, np.eye(3))
    h, w, _ = latlong.shape
    assert h >= 4 * n and set(np.unique(latlong)) == {0.0, 1000.0}
    theta = (np.arange(h) + 0.5) / h * np.pi
    solid_angle = (latlong[..., 0] > 0) @ np.ones(w) @ np.sin(theta) * (np.pi / h) * (2 * np.pi / w)
    assert solid_angle == pytest.approx(4 * np.pi / n ** 2, rel=0.03)


def test_an_imagemaps_default_encoding_is_srgb_for_png_only(tmp_path):
    """pbrt-v4 SpectrumImageTexture::Create: encoding "sRGB" for a .png, else "linear"."""
    from PIL import Image
    for suffix in ("png", "tga"):
        Image.fromarray(np.full((2, 2, 3), 128, np.uint8)).save(tmp_path / f"t.{suffix}")
    linear = {}
    for suffix in ("png", "tga"):
        s = scene(tmp_path, f'Texture "t" "spectrum" "imagemap" "string filename" "t.{suffix}"\n'
                            'Material "diffuse" "texture reflectance" "t"\n' + FLOOR)
        linear[suffix] = s.materials.get(s.meshes[0].material).params["rho_d"].params["image"].linear
    assert linear == {"png": False, "tga": True}


def test_an_area_light_on_an_interface_shape_is_no_light(tmp_path, capsys):
    """pbrt-v4 scene.cpp: 'Ignoring area light specification for shape with "interface"
    material.' The shape still bounds its media."""
    s = scene(tmp_path, 'MakeNamedMedium "fog" "string type" "homogeneous"\n'
                        'AttributeBegin\nMaterial "interface"\nMediumInterface "fog" ""\n'
                        'AreaLightSource "diffuse" "rgb L" [ 5 5 5 ]\nShape "sphere"\nAttributeEnd\n' + FLOOR)
    assert "makes no area light of a shape of the interface material" in capsys.readouterr().err
    assert all(not np.any(s.materials.get(r).emission > 0) for r in range(len(s.materials)))
    assert len(s.spheres) == 1


def test_an_infinite_lights_illuminance_scales_it_as_pbrt(tmp_path):
    """pbrt-v4 Light::Create: a constant L times illuminance / pi; a map times illuminance over
    the sum, over its texels above the horizon (z > 0), of luminance cos theta 2 pi / N^2."""
    from pathtrace.io.images import _write_exr
    from pathtrace.scene.pbrt.equal_area import sphere_to_square, square_to_sphere
    rng = np.random.default_rng(2)
    d = rng.normal(size=(1000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    assert np.allclose(square_to_sphere(sphere_to_square(d)), d, atol=1e-9)
    s = scene(tmp_path, 'LightSource "infinite" "rgb L" [ 0.5 1 1 ] "float illuminance" 3\n' + FLOOR)
    assert np.allclose(s.environment.image.reshape(-1, 3)[0] * s.environment.intensity, np.array([0.5, 1, 1]) * 3 / math.pi)
    n = 64
    _write_exr(str(tmp_path / "sky.exr"), np.full((n, n, 3), 2.0, np.float32))
    s = scene(tmp_path, 'LightSource "infinite" "string filename" "sky.exr" "float illuminance" 3\n' + FLOOR)
    # a uniform map of c: c (pi / 2) in pbrt's sum (the upper half's mean cosine, 1/2, times 2 pi / 2)
    assert float(np.mean(s.environment.image) * s.environment.intensity) == pytest.approx(3 / (math.pi / 2), rel=0.01)
