"""blendbsdf (app/materials/blend.py, kernels/bsdfs/blendbsdf.cl): Mitsuba 3's blendbsdf and
pbrt-v4's mix, one component taken per hit. Its image against Mitsuba's is in
test_reference.py (tests/scenes/blend.xml)."""

import numpy as np
import pytest

from pathtrace.compiler.compiled import CompiledScene
from pathtrace.errors import UserError
from pathtrace.materials import Material, MaterialTable
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene

SCENE = """
[camera]
eye = [0, 0, 3]
look_at = [0, 0, 0]
vfov = 30
[environment]
color = [1, 1, 1]
[materials]
red = {{ type = "diffuse", rho_d = [0.8, 0.2, 0.1] }}
mirror = {{ type = "conductor" }}
{extra}
[[spheres]]
center = [0, 0, 0]
radius = 1
material = {material}
"""


def scene(tmp_path, material, extra=""):
    (tmp_path / "s.toml").write_text(SCENE.format(material=material, extra=extra))
    return load_scene(str(tmp_path / "s.toml"))


def image(backend, s, spp=256):
    r = Renderer(backend, s.with_settings(max_depth=4, russian_roulette="off"), 24, 24)
    r.add_samples(spp)
    return r.mean(), r.variance() / r.samples


def test_a_blend_renders_the_weighted_mean_of_its_components(backend, tmp_path):
    """Under a white sky, a blend of weight w is (1 - w) times its first component's image plus
    w times its second's, within their noise: the choice per hit is the mixture in expectation."""
    w = 0.3
    blend, var = image(backend, scene(tmp_path, f'{{ type = "blendbsdf", weight = {w}, bsdfs = ["red", "mirror"] }}'))
    red, var_red = image(backend, scene(tmp_path, '"red"'))
    mirror, var_mirror = image(backend, scene(tmp_path, '"mirror"'))
    expected = (1 - w) * red + w * mirror
    z = (blend - expected) / np.sqrt(var + (1 - w) ** 2 * var_red + w ** 2 * var_mirror + 1e-12)
    assert abs(float(np.mean(z))) * np.sqrt(z.size) < 5 and np.mean(np.abs(z) > 4) < 0.01


def test_table_rows_of_components_are_reused_and_read_back(tmp_path):
    s = scene(tmp_path, '"mix"', 'mix = { type = "blendbsdf", weight = 0.25, bsdfs = ["red", '
                                 '{ type = "blendbsdf", bsdfs = ["mirror", "red"] }] }')
    table: MaterialTable = s.materials
    m = table["mix"]
    assert m.type == "blendbsdf" and m.params["weight"] == pytest.approx(0.25)
    assert [c.type for c in m.components] == ["diffuse", "blendbsdf"]
    assert [c.type for c in m.components[1].components] == ["conductor", "diffuse"]
    rows = len(table)
    m.params["weight"] = 0.75
    table["mix"] = m
    assert len(table) == rows and table["mix"].params["weight"] == pytest.approx(0.75)


def test_only_scenes_with_a_blend_compile_its_choice_and_its_components_types(tmp_path):
    def features(material):
        s = scene(tmp_path, material)
        return CompiledScene(s).features(s.settings, s.camera)
    f = features('{ type = "blendbsdf", bsdfs = ["red", { type = "roughconductor", alpha = 0.2, alpha_v = 0.05 }] }')
    assert "BLEND" in f.defines() and "ANISOTROPIC" in f.defines()
    assert {"blendbsdf", "diffuse", "roughconductor"} <= set(f.bsdfs)
    assert "BLEND" not in features('"red"').defines()


def test_a_material_edit_changes_the_features_of_a_compiled_scene(tmp_path):
    """features() keeps its materials' kinds for the table it was computed from (material_kinds)
    and computes them again after an edit (update_materials): a blend put in the place of a
    diffuse material brings its choice and its components' types."""
    s = scene(tmp_path, '"red"')
    compiled = CompiledScene(s)
    before = compiled.features(s.settings, s.camera)
    assert "BLEND" not in before.defines() and compiled.features(s.settings, s.camera) == before
    row = next(i for i in range(len(s.materials)) if s.materials.rows["type"][i] == s.materials.rows["type"][
        compiled.shape_materials[0]])
    s.materials.set(row, Material("blendbsdf", {"weight": 0.5}, components=[
        Material("diffuse", {"rho_d": 0.5}), Material("roughconductor", {"alpha": 0.2})]))
    compiled.update_materials()
    after = compiled.features(s.settings, s.camera)
    assert "BLEND" in after.defines() and {"blendbsdf", "roughconductor"} <= set(after.bsdfs)


@pytest.mark.parametrize("material,message", [
    ('{ type = "blendbsdf", weight = 1.5, bsdfs = ["red", "mirror"] }', "weight"),
    ('{ type = "blendbsdf", bsdfs = ["red"] }', "must be a list of two materials"),
    ('{ type = "blendbsdf", bsdfs = ["red", "nothing"] }', "no material named 'nothing'"),
    ('{ type = "blendbsdf", bsdfs = ["red", { type = "null" }] }', "cannot mix in a null material"),
    ('{ type = "blendbsdf", bsdfs = ["red", { type = "diffuse", rho_d = 0.5, opacity = 0.5 }] }',
     "cannot have an opacity"),
    ('{ type = "blendbsdf", bsdfs = ["red", { type = "dielectric" }] }', "cannot mix a transmissive material"),
    ('{ type = "blendbsdf", twosided = true, bsdfs = [{ type = "dielectric" }, { type = "roughdielectric" }] }',
     "cannot be two-sided"),
    ('"loop"', "a reference cycle"),
])
def test_bad_blends_are_one_line(tmp_path, material, message):
    extra = 'loop = { type = "blendbsdf", bsdfs = ["red", "loop"] }' if "loop" in material else ""
    with pytest.raises(UserError) as e:
        scene(tmp_path, material, extra)
    assert message in str(e.value) and "\n" not in str(e.value)


def test_blends_nest_at_most_eight_deep():
    m = Material("diffuse", {"rho_d": 0.5})
    for _ in range(9):
        m = Material("blendbsdf", {"weight": 0.5}, components=(m, Material("diffuse", {"rho_d": 0.1})))
    with pytest.raises(ValueError, match="nest deeper than 8"):
        MaterialTable().add(m)


def test_pbrt_mix_is_a_blend_whose_amount_is_the_weight(tmp_path):
    (tmp_path / "s.pbrt").write_text(
        'Camera "perspective"\nWorldBegin\n'
        'MakeNamedMaterial "a" "string type" "diffuse"\n'
        'MakeNamedMaterial "b" "string type" "conductor" "float roughness" 0.01\n'
        'MakeNamedMaterial "m" "string type" "mix" "string materials" ["a" "b"] "float amount" 0.2\n'
        'NamedMaterial "m"\nShape "sphere"\n')
    s = load_scene(str(tmp_path / "s.pbrt"))
    m = s.materials.get(int(s.sphere_material[0]))
    assert m.type == "blendbsdf" and m.params["weight"] == pytest.approx(0.2) and m.twosided
    assert [c.type for c in m.components] == ["diffuse", "roughconductor"]
    # its amount read by the blend's declaration (weight: pbrt-v4's amount), checked in its range
    (tmp_path / "s.pbrt").write_text((tmp_path / "s.pbrt").read_text().replace('"float amount" 0.2', '"float amount" 1.5'))
    with pytest.raises(UserError, match=r"s\.pbrt:5: 'amount': must lie in \[0, 1\], got 1.5"):
        load_scene(str(tmp_path / "s.pbrt"))
