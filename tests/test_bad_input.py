"""Bad input met as pbrt-v4 and the Python API meet it (#61), each case with the message it must
give: the file's line and the number as the file wrote it, or the API's field by name; and the
reader's work bounded by what a file holds, not by products of counts (tests/test_fuzz_inputs.py
fuzzes the same classes)."""

import numpy as np
import pytest

import pathtrace
from pathtrace.errors import UserError
from pathtrace.materials.table import MaterialTable
from pathtrace.scene import load_scene
from pathtrace.scene.pbrt.reader import PbrtReader
from pathtrace.scene.pbrt.state import MAX_INCLUDES
from pathtrace.device.types import MATERIAL

HEAD = 'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\n'
TRIANGLE = 'Shape "trianglemesh" "point3 P" [ -1 -1 0  1 -1 0  0 1 0 ] "integer indices" [ 0 1 2 ]\n'
TINY = 'Scale 1e-200 1e-200 1e-200\nScale 1e-200 1e-200 1e-200\n'     # factors whose product is 0


def refusal(tmp_path, text) -> str:
    (tmp_path / "s.pbrt").write_text(text)
    with pytest.raises(UserError) as e:
        load_scene(str(tmp_path / "s.pbrt"))
    return str(e.value)


def _pfm(path, value):
    path.write_bytes(b"PF\n2 2\n-1.0\n" + np.full((2, 2, 3), value, np.float32).tobytes())


@pytest.mark.parametrize("text,expected", [
    (TINY + HEAD + TRIANGLE, "s.pbrt:4: the camera needs the current transform's inverse"),
    (HEAD + 'AttributeBegin\n' + TINY + 'LightSource "infinite" "string filename" "sky.pfm"\nAttributeEnd\n' + TRIANGLE,
     "s.pbrt:7: an infinite light's map needs the current transform's inverse"),
    (HEAD + 'Material "mix" "float amount" 0.5\n' + TRIANGLE, 's.pbrt:4: a mix material needs "string materials"'),
    (HEAD + 'AreaLightSource "diffuse" "float scale" -1\n' + TRIANGLE, "s.pbrt:4: 'scale': an emitted radiance"),
    (HEAD + 'LightSource "infinite" "float scale" -1\n' + TRIANGLE, "s.pbrt:4: 'scale': must not be negative"),
    (HEAD + TRIANGLE.replace("0 1 2 ]", "0 1 1e20 ]"), "'indices': integer values must fit in 32 bits, got 1e20"),
    (HEAD + TRIANGLE.replace("0 1 2 ]", "0 1 9223372036854775808 ]"), "got 9223372036854775808"),
    (HEAD + 'AreaLightSource "diffuse" "float power" 100\n'
     + TRIANGLE.replace("-1 -1 0  1 -1 0  0 1 0", "0 0 0  1e-30 0 0  0 1e-30 0"), "'power' 100 over the shape's area of"),
    (HEAD + 'AreaLightSource "diffuse" "blackbody L" [ 1e-30 ]\n' + TRIANGLE, "'L': a blackbody of 1e-30 K emits no"),
    (HEAD + 'AreaLightSource "diffuse" "spectrum L" [ 400 0 700 0 ]\n' + TRIANGLE, "'L': the spectrum emits no"),
    (HEAD + TRIANGLE.replace("]\n", '] "float alpha" nan\n'), "s.pbrt:4: 'alpha': nan is not finite"),
    (HEAD + 'Texture "a" "float" "imagemap" "string filename" "huge.pfm"\n' + TRIANGLE.replace("]\n", '] "texture alpha" "a"\n'),
     "s.pbrt:5: 'alpha': must lie in [0, 1], got 3e+38"),      # a texture by its bounds
])
def test_bad_pbrt_input_is_one_line_with_the_files_line_and_numbers(tmp_path, text, expected):
    _pfm(tmp_path / "sky.pfm", 0.5)
    _pfm(tmp_path / "huge.pfm", 3e38)
    message = refusal(tmp_path, text)
    assert "s.pbrt" in message and expected in message, message


def test_a_shape_or_an_instance_under_a_singular_transform_is_left_out_with_a_warning(tmp_path, capsys):
    (tmp_path / "s.pbrt").write_text(
        HEAD + TRIANGLE + 'ObjectBegin "o"\n' + TRIANGLE + 'ObjectEnd\n'
        + 'AttributeBegin\n' + TINY + TRIANGLE.replace(" ]\n", ' ] "normal N" [ 0 0 1  0 0 1  0 0 1 ]\n')
        + 'Shape "sphere"\nObjectInstance "o"\nAttributeEnd\n')
    s = load_scene(str(tmp_path / "s.pbrt"))
    assert s.triangle_count == 1 and len(s.spheres) == 0 and s.instances is None
    lines = capsys.readouterr().err.splitlines()
    # the two shapes' warnings alike, told once with their count; the instance's
    assert len(lines) == 2 and all("singular" in line and "leaves" in line for line in lines), lines
    assert "2 like this" in lines[0] and "s.pbrt:11: " in lines[0] and "s.pbrt:13: " in lines[1], lines


@pytest.mark.parametrize("singular", ['Scale 0 1 1\n', 'Transform [ 1 0 0 0  0 0 0 0  0 0 1 0  0 0 0 1 ]\n'],
                         ids=["zero-scale", "singular-transform"])
def test_a_zero_scale_or_a_singular_transform_is_taken_as_a_product_that_underflows(tmp_path, capsys, singular):
    """pbrt-v4 takes both (it carries an inverse of infinities): as for factors whose product is
    0, a camera under one is refused and a shape is left out with a warning, where the reader
    refused the directive itself (a new user's run, 2026-12-03, against docs/pbrt.md)."""
    assert "s.pbrt:3: the camera needs the current transform's inverse" in refusal(tmp_path, singular + HEAD + TRIANGLE)
    (tmp_path / "s.pbrt").write_text(HEAD + TRIANGLE + 'AttributeBegin\n' + singular + TRIANGLE + 'AttributeEnd\n')
    assert load_scene(str(tmp_path / "s.pbrt")).triangle_count == 1
    assert "s.pbrt:7: the current transform is singular" in capsys.readouterr().err


def test_a_light_with_directions_under_a_singular_transform_is_left_out_with_a_warning(tmp_path, capsys):
    """Its directions went through the flattening matrix, and the line blamed a parameter the
    file gave as non-zero ("'to': must not be zero"); a point light's position survives it."""
    (tmp_path / "s.pbrt").write_text(
        HEAD + TRIANGLE + 'AttributeBegin\nScale 1 1 0\n'
        'LightSource "distant" "point3 from" [0 0 0] "point3 to" [0 0 1]\n'
        'LightSource "point" "point3 from" [0 1 0]\nAttributeEnd\n')
    s = load_scene(str(tmp_path / "s.pbrt"))
    assert [light.name for light in s.lights] == ["point"]
    assert "s.pbrt:7: the current transform is singular (it flattens the light's directions)" in capsys.readouterr().err


def test_warnings_alike_are_told_once_with_their_count(tmp_path, capsys):
    (tmp_path / "s.pbrt").write_text(HEAD + TRIANGLE + 'Shape "curve"\n' * 3000)
    load_scene(str(tmp_path / "s.pbrt"))
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("pathtrace: warning: 3000 like this; the first: ") \
        and "s.pbrt:5: pathtrace has no curve shape" in lines[0], lines


def test_objects_are_made_at_their_first_instance_only(tmp_path):
    objects = "".join(f'ObjectBegin "o{i}"\n{TRIANGLE}ObjectEnd\n' for i in range(500))
    (tmp_path / "s.pbrt").write_text(HEAD + TRIANGLE + objects + 'ObjectInstance "o7"\nTranslate 1 0 0\nObjectInstance "o7"\n')
    reader = PbrtReader(tmp_path / "s.pbrt")
    s = reader.read()
    assert [o.name for o in reader.builder.objects] == ["o7"]
    assert len(s.instances.object) == 2 and s.instances.objects[0].triangle_count == 1


def test_attribute_blocks_without_a_material_share_the_default_one(tmp_path):
    (tmp_path / "s.pbrt").write_text(HEAD + f"AttributeBegin\n{TRIANGLE}AttributeEnd\n" * 2000)
    s = load_scene(str(tmp_path / "s.pbrt"))
    assert s.triangle_count == 2000 and len(s.materials) == 1


def test_the_material_table_grows_by_rows_keeping_each(tmp_path):
    t = MaterialTable()
    for k in range(100):
        row = np.zeros(1, MATERIAL)
        row["continuation"] = k
        t.add_rows(row)
    copy = t.copy()
    copy.add_rows(np.zeros(3, MATERIAL))
    assert len(t) == 100 and len(copy) == 103
    assert np.array_equal(t.rows["continuation"], np.arange(100)) and np.array_equal(
        copy.rows["continuation"][:100], np.arange(100))


def test_includes_are_limited_in_all_not_only_in_depth(tmp_path):
    for level in range(6):          # 5 wide, 6 deep: 19,530 reads, past the limit
        (tmp_path / f"f{level}.pbrt").write_text(
            "" if level == 5 else f'Include "f{level + 1}.pbrt"\n' * 5)
    message = refusal(tmp_path, HEAD + TRIANGLE + 'Include "f0.pbrt"\n' * 5)
    assert f"more than {MAX_INCLUDES} Includes in all" in message, message


BASE = {"camera": {"eye": [0, 1, 5], "look_at": [0, 0, 0]}, "render": {"spp": 1, "width": 8, "height": 6},
        "spheres": [{"center": [0, 0, 0], "radius": 1, "material": {"type": "diffuse", "rho_d": 0.5}}],
        "meshes": [{"vertices": [[-2, -1, -2], [2, -1, -2], [0, -1, 2]], "faces": [[0, 1, 2]],
                    "material": {"type": "diffuse", "rho_d": 0.5}}]}


def _settings_width(s):
    s.settings.width = 0


def _seed(s):
    s.settings.seed = -1


def _rr(s):
    s.settings.russian_roulette = "nosuch"


def _nan_sphere(s):
    s.spheres[0, :3] = np.nan


def _faces(s):
    s.meshes[0].faces[0, 0] = 99


def _eye(s):
    s.camera.look_at = s.camera.eye.copy()


@pytest.mark.parametrize("change,expected", [
    (_settings_width, "scene.settings.width: give an integer from 1 to 16384, got 0"),
    (_seed, "scene.settings.seed"), (_rr, "scene.settings.russian_roulette"), (_nan_sphere, "scene.spheres[0]"),
    (_faces, "scene.meshes[0].faces[0]: refers to vertex [99, 1, 2]"), (_eye, "scene.camera.look_at"),
])
def test_a_scene_changed_after_loading_is_checked_at_render_naming_the_field(change, expected):
    s = pathtrace.load_dict(BASE)
    change(s)
    with pytest.raises(UserError) as e:
        pathtrace.render(s, device="cpu")
    assert expected in str(e.value), str(e.value)


@pytest.mark.parametrize("call,expected", [
    (lambda: pathtrace.render(pathtrace.load_dict(BASE), device=2.5), "device:"),
    (lambda: pathtrace.render(pathtrace.load_dict(BASE), aovs=1), "aovs:"),
    (lambda: list(pathtrace.progressive(pathtrace.load_dict(BASE), steps=1)), "steps:"),
    (lambda: pathtrace.write(1, np.zeros((2, 2, 3))), "path:"),
    (lambda: pathtrace.tonemap(object()), "image:"),
    (lambda: pathtrace.load_dict({**BASE, 1: 2}), "keys must be strings"),
])
def test_odd_arguments_are_user_errors_naming_the_argument(call, expected):
    with pytest.raises(UserError) as e:
        call()
    assert expected in str(e.value), str(e.value)


def test_a_dict_that_holds_itself_or_nests_deep_is_refused():
    d = {"camera": {}}
    d["camera"]["self"] = d
    with pytest.raises(UserError, match="holds itself"):
        pathtrace.load_dict(d)
    deep = x = {}
    for _ in range(5000):
        x["a"] = {}
        x = x["a"]
    with pytest.raises(UserError, match="nested more than"):
        pathtrace.load_dict({"spheres": [{"center": [0, 0, 0], "radius": 1, "material": deep}]})


def test_an_analytic_shape_too_near_flat_to_trace_is_left_out_with_a_warning(tmp_path, capsys):
    """A sphere or a disk under a transform that is not singular but whose determinant is below
    what the kernels' inverse holds (pathtrace.shapes.shape.MIN_DETERMINANT): left out, as a
    singular one is, rather than refused at render naming no line."""
    (tmp_path / "s.pbrt").write_text(HEAD + TRIANGLE + 'AttributeBegin\nScale 1e-30 1 1\nShape "sphere"\n'
                                     'Shape "disk"\nAttributeEnd\n')
    s = load_scene(str(tmp_path / "s.pbrt"))
    assert s.triangle_count == 1 and len(s.spheres) == 0 and not s.shapes
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and "singular" in lines[0] and "2 like this" in lines[0], lines


def test_a_mitsuba_analytic_shape_too_near_flat_is_left_out_with_the_line_that_placed_it(tmp_path, capsys):
    """As in pbrt: Mitsuba 3 would intersect it through its near-singular inverse; the kernels
    cannot, so it is left out with a warning naming its line, not refused at render naming
    scene.shapes[i]. A tiny sphere is such a shape where it stays analytic (its normals flipped),
    and kept where the sphere range, which needs no inverse, renders it."""
    (tmp_path / "s.xml").write_text(
        '<scene version="3.0.0">\n<shape type="rectangle"/>\n'
        '<shape type="disk"><transform name="to_world"><scale x="1e-13" y="1" z="1"/></transform></shape>\n'
        '<shape type="sphere"><boolean name="flip_normals" value="true"/>'
        '<transform name="to_world"><scale value="1e-5"/></transform></shape>\n'
        '<shape type="sphere"><transform name="to_world"><scale value="1e-5"/></transform></shape>\n</scene>\n')
    s = load_scene(str(tmp_path / "s.xml"))
    assert s.triangle_count == 2 and len(s.spheres) == 1 and not s.shapes
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2 and all("leaves it out" in line for line in lines), lines
    assert "s.xml:3:" in lines[0] and "disk" in lines[0] and "s.xml:4:" in lines[1] and "sphere" in lines[1], lines


def test_a_toml_analytic_shape_too_near_flat_is_refused_naming_the_shape(tmp_path):
    (tmp_path / "s.toml").write_text('[materials]\nm = {type = "diffuse", rho_d = 0.5}\n'
                                     '[[shapes]]\nkind = "disk"\nmaterial = "m"\nscale = [1e-13, 1, 1]\n')
    with pytest.raises(UserError) as e:
        load_scene(str(tmp_path / "s.toml"))
    assert "s.toml" in str(e.value) and "shapes[0]" in str(e.value) and "flattens the disk" in str(e.value)


def test_a_tiny_pbrt_sphere_stays_in_the_sphere_range(tmp_path, capsys):
    """Too small for an analytic shape's inverse, but whole and placed by a similarity: the sphere
    range, which needs no inverse, renders it, so it is kept without a warning."""
    (tmp_path / "s.pbrt").write_text(HEAD + TRIANGLE + 'AttributeBegin\nScale 1e-5 1e-5 1e-5\nShape "sphere"\nAttributeEnd\n')
    s = load_scene(str(tmp_path / "s.pbrt"))
    assert len(s.spheres) == 1 and not s.shapes and capsys.readouterr().err == ""


@pytest.mark.parametrize("table", ["camera", "environment", "render", "lights", "objects"])
def test_a_top_level_table_given_as_a_number_is_refused_naming_it(table):
    """Found by tests/test_fuzz_scenes.py: `camera = 0` was a traceback."""
    with pytest.raises(UserError) as e:
        pathtrace.load_dict({**BASE, table: 0})
    assert f"'scene': {table}: must be" in str(e.value), str(e.value)


@pytest.mark.parametrize("le,expected", [
    (1e25, "materials.lamp.Le: must be in [0, 1e+20], got 1e+25"),
    ({"type": "mix", "tex1": 1.0, "tex2": 0.0, "amount": 1.5},
     "materials.lamp.Le: the texture's values must lie in [0, 1e+20], got -0.5"),    # (1 - 1.5) 1 + 1.5 0
    ({"type": "mix", "tex1": 2e20, "tex2": 2e20, "amount": 1e17},       # 2e20 whatever the amount
     "materials.lamp.Le: the texture's values must lie in [0, 1e+20], got 2e+20"),
    (1e20, None), ("environment", None),
])
def test_an_emitters_radiance_is_checked_where_the_file_gives_it(le, expected):
    """Radiance beyond 1e20 (where the sums of samples overflow) or below 0, a mix texture's
    amount beyond [0, 1] extrapolating too, is refused naming the field that gives it; 1e20
    itself, which the field's bound lets through in float32, renders, from a lamp and from the
    environment."""
    scene = {**BASE, "materials": {"lamp": {"type": "emitter", "Le": le}},
             "spheres": [{"center": [0, 0, 0], "radius": 1, "material": "lamp"}]}
    if le == "environment":
        scene = {**BASE, "environment": {"color": 1e20}}
    if expected is None:
        assert np.isfinite(pathtrace.render(pathtrace.load_dict(scene, "hot"), spp=1, size=(4, 4), device="cpu")).all()
        return
    with pytest.raises(UserError) as e:
        pathtrace.load_dict(scene, "hot")
    assert str(e.value) == f"scene dict 'hot': {expected}"
