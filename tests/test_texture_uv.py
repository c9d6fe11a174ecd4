"""A shape's texture coordinates of its kind's (u, v) (app/shapes/texture_uv.py): every mode of
every registered kind gives hits the mode's formula of the kind's (u, v), and tangents dp/du,
dp/dv along those texture coordinates (finite differences of the hit points); the TOML
reader and writer carry each mode round; a bad value is one line naming the field."""

import numpy as np
import pytest

from pathtrace.errors import UserError
from pathtrace.scene import load_scene, transform
from pathtrace.scene.toml_writer import scene_toml
from pathtrace.shapes import SHAPES, Shape, TextureUV
from tests.analytic_shapes import moved
from tests.test_shapes import one_shape_scene, shape_hits

# each mode's texture coordinates of the kind's (u, v), as its TOML value reads
FORMULAS = {"u,v": lambda u, v: (u, v), "1-v,u": lambda u, v: (1 - v, u), "u,1-v": lambda u, v: (u, 1 - v)}

STEP = 2e-3          # how far, in the shape's size, the second ray of a pair is aimed from the first's hit


def test_every_mode_has_its_formula():
    assert sorted(m.value for m in TextureUV) == sorted(FORMULAS)
    assert list(TextureUV)[0] is TextureUV.KIND         # the default, which a file leaves out


@pytest.mark.parametrize("kind", list(SHAPES))
@pytest.mark.parametrize("mode", list(TextureUV))
def test_texture_uv_and_derivatives_follow_the_mode(kernels, kind, mode):
    """Under an uneven scale and a turn, each mode's hits carry its formula of the kind's own
    (u, v) (the same rays with the kind's mode), and its dp/du, dp/dv are the derivatives of
    the point along those coordinates: between two hits about STEP apart, p2 - p1 = (J1 + J2) / 2
    (uv2 - uv1) with J = [dp/du dp/dv], to second order in the step (the trapezoid rule), where
    a tangent swapped or turned round is wrong by the whole step. Pairs across u's seam, or near
    a pole or a centre, where a derivative vanishes, are left out."""
    rng = np.random.default_rng(11)
    m = transform.translation([0.4, -0.3, 0.8]) @ transform.rotation([1, 2, 0], 35) @ transform.scaling([0.7, 1.4, 1.1])
    params = SHAPES[kind].examples[-1]
    scene = one_shape_scene(Shape("s", kind, params, m, 0, texture_uv=mode))
    lo, hi = SHAPES[kind].object_bounds(params)
    targets = moved(m, rng.uniform(lo, hi, (4000, 3)))
    origins = targets + 6 * rng.normal(size=(4000, 3))
    own = shape_hits(kernels, one_shape_scene(Shape("s", kind, params, m, 0)), origins, targets)
    a = shape_hits(kernels, scene, origins, targets)
    met = ~np.isnan(a["p"][:, 0])
    assert met.mean() > 0.3
    np.testing.assert_allclose(a["uv"][met], np.column_stack(FORMULAS[mode.value](*own["uv"][met].T)), atol=1e-6)

    a = {k: v[met] for k, v in a.items()}
    lo, hi = scene.shapes[0].bounds(SHAPES[kind])
    size = float(np.linalg.norm(hi - lo))
    tangent = np.cross(a["n"], rng.normal(size=(len(a["n"]), 3)))
    tangent *= STEP * size / np.linalg.norm(tangent, axis=1, keepdims=True)
    b = shape_hits(kernels, scene, origins[met], a["p"] + tangent)
    duv, dp = b["uv"] - a["uv"], b["p"] - a["p"]
    step = np.linalg.norm(dp, axis=1)
    lengths = np.linalg.norm(np.stack([a["dpdu"], a["dpdv"], b["dpdu"], b["dpdv"]]), axis=2)
    keep = (~np.isnan(step) & (step > 0.3 * STEP * size) & (step < 2 * STEP * size)
            & (np.abs(duv).max(axis=1) < 0.1) & (lengths.min(axis=0) > 0.2 * size))
    assert keep.sum() > 500
    du, dv = duv[keep, :1], duv[keep, 1:]
    predicted = (du * (a["dpdu"][keep] + b["dpdu"][keep]) + dv * (a["dpdv"][keep] + b["dpdv"][keep])) / 2
    # float32's rounding of points ~3 from the origin, 4e-7, is 1e-4 of a step of 4e-3 (size ~2);
    # the trapezoid rule's error is of order the step squared; a wrong tangent is 1 (or 2)
    residual = np.linalg.norm(dp[keep] - predicted, axis=1) / step[keep]
    assert residual.max() < 1e-3, np.sort(residual)[-5:]


SCENE = """[camera]
type = "perspective"
eye = [0, 0, 5]
look_at = [0, 0, 0]
[materials]
m = {{ type = "diffuse", rho_d = 0.5 }}
[[shapes]]
kind = "disk"
material = "m"
{line}
"""


@pytest.mark.parametrize("mode", list(TextureUV))
def test_toml_reads_writes_and_reads_back_each_mode(tmp_path, mode):
    path = tmp_path / "a.toml"
    path.write_text(SCENE.format(line=f'texture_uv = "{mode.value}"'))
    (shape,) = load_scene(str(path)).shapes
    assert shape.texture_uv is mode
    out = tmp_path / "b.toml"
    out.write_text(scene_toml(load_scene(str(path)), out))
    (back,) = load_scene(str(out)).shapes
    assert back.texture_uv is mode
    assert ("texture_uv" in out.read_text()) == (mode is not TextureUV.KIND)


def test_a_shape_without_texture_uv_has_its_kinds(tmp_path):
    path = tmp_path / "a.toml"
    path.write_text(SCENE.format(line=""))
    assert load_scene(str(path)).shapes[0].texture_uv is TextureUV.KIND


@pytest.mark.parametrize("line, field", [('texture_uv = "v,u"', "shapes[0].texture_uv"),
                                         ("texture_uv = 2", "shapes[0].texture_uv"),
                                         ("swap_uv = true", "swap_uv")])
def test_a_bad_texture_uv_is_one_line_naming_the_field(tmp_path, line, field):
    path = tmp_path / "bad.toml"
    path.write_text(SCENE.format(line=line))
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    assert field in str(e.value) and "\n" not in str(e.value)

