"""app/bench/divergence_stats.py: the host's grouping of the records into warps against hand-built
records whose answers are known, and the stats build (kernels/divergence.cl) on scenes whose
shading is known per pixel, which records without changing a sample."""

import json

import numpy as np
import pyopencl as cl
import pytest

from pathtrace.bench.divergence_stats import FIELDS, SHADING_BSDF, Tally, check_warp, divergence_stats
from pathtrace.cameras import PerspectiveCamera
from pathtrace.errors import UserError
from pathtrace.materials import Material
from pathtrace.materials.registry import TAGS
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import Mesh, SceneBuilder, diffuse, emitter, phong
from pathtrace.scene.environment import Environment
from tests.commands import in_process

DIFFUSE, PHONG = SHADING_BSDF + TAGS["diffuse"], SHADING_BSDF + TAGS["phong"]
SHADING, TEXTURES, LIGHT, MATERIAL_LOW, MATERIAL_HIGH = range(len(FIELDS))


def records(shading, textures=None, light=None, went_on=None, materials=None):
    """Records of one sample and len(shading) iterations, each a row of lanes, and the row that
    says which paths went on past them; the lanes that shade a BSDF shade material row 0 unless
    `materials` gives their rows."""
    rows = np.zeros((1, len(shading) + 1, len(FIELDS), len(shading[0])), np.uint8)
    rows[0, :-1, SHADING] = shading
    shaded = np.asarray(shading) >= SHADING_BSDF
    row = np.where(shaded, 1 + (np.asarray(materials) if materials is not None else 0), 0)
    rows[0, :-1, MATERIAL_LOW], rows[0, :-1, MATERIAL_HIGH] = row & 255, row >> 8
    if textures is not None:
        rows[0, :-1, TEXTURES] = textures
    if light is not None:
        rows[0, :-1, LIGHT] = light
    if went_on is not None:
        rows[0, -1, SHADING] = went_on
    return rows


def stats_of(rows, warp=32, paths=None):
    tally = Tally(rows.shape[1] - 1, warp)
    tally.add(rows)
    return tally.stats(paths or rows.shape[-1])


def branch(stats, name):
    return next(b for b in stats.branches if b.name == name)


def test_lanes_of_one_material_use_the_whole_warp():
    s = stats_of(records([[DIFFUSE] * 64]))
    o = s.overall
    assert (o.executions, o.active_share, o.shading_efficiency, o.bsdf_efficiency, o.distinct_bsdfs) == (2, 1, 1, 1, 1)
    assert branch(s, "bsdf diffuse").efficiency == 1 and o.light_efficiency is None and s.unrecorded == 0


def test_alternate_lanes_of_two_materials_use_half_the_warp_each():
    s = stats_of(records([[DIFFUSE, PHONG] * 32]))
    assert s.overall.active_share == 1 and s.overall.bsdf_efficiency == 0.5 and s.overall.distinct_bsdfs == 2
    assert branch(s, "bsdf diffuse").efficiency == branch(s, "bsdf phong").efficiency == 0.5
    assert branch(s, "bsdf diffuse").executions == 2 and branch(s, "bsdf diffuse").lanes == 32
    assert s.overall.distinct_materials == 1          # both types' lanes of the one row 0


def test_materials_of_one_type_count_apart():
    """Rows 300 and 44 share their low byte once 1 is added (45): the high byte tells them apart."""
    s = stats_of(records([[DIFFUSE] * 64], materials=[[300, 44] * 32]))
    assert s.overall.distinct_bsdfs == 1 and s.overall.bsdf_efficiency == 1 and s.overall.distinct_materials == 2
    s = stats_of(records([[DIFFUSE] * 32 + [2] * 32], materials=[[7] * 64]))
    assert s.overall.distinct_materials == 1 and s.overall.executions == 2   # an escaped warp shades none


def test_the_warp_width_decides_what_shares_a_warp():
    halves = records([[DIFFUSE] * 32 + [PHONG] * 32])
    assert stats_of(halves, 32).overall.distinct_bsdfs == 1 and stats_of(halves, 32).overall.bsdf_efficiency == 1
    assert stats_of(halves, 64).overall.distinct_bsdfs == 2 and stats_of(halves, 64).overall.bsdf_efficiency == 0.5
    with pytest.raises(UserError, match="48 lanes"):
        check_warp(48)


def test_idle_lanes_textures_lights_and_iterations():
    """Iteration 0: a warp of 32 lanes, the first 8 escaped, 24 shaded (16 with two texture
    lookups each, all 24 sampling an area light), a second warp idle all along (never run);
    iteration 1: 4 lanes of the first warp shade, 2 of which go on past the records."""
    area = 1 + 0     # 1 + LIGHT_AREA (app/lights/registry.py: LIGHTS[0])
    first = [2] * 8 + [DIFFUSE] * 24 + [0] * 32
    lookups = [0] * 8 + [2] * 16 + [0] * 40
    lights = [0] * 8 + [area] * 24 + [0] * 32
    second = [DIFFUSE] * 4 + [0] * 60
    s = stats_of(records([first, second], [lookups, [0] * 64], [lights, [0] * 64], [1, 1] + [0] * 62), paths=64)
    it0, it1 = s.per_iteration
    assert (it0.executions, it0.active_share, it0.bsdf_efficiency, it0.light_efficiency) == (1, 1, 0.75, 0.75)
    assert it0.shading_efficiency == 32 / (32 * 2)                  # the escaped and the diffuse branch
    assert it0.texture_lookups_per_ray == 32 / 32 and branch(s, "image textures").efficiency == 0.5
    assert (it1.executions, it1.active_share, it1.bsdf_efficiency) == (1, 4 / 32, 4 / 32)
    assert s.overall.executions == 2 and s.overall.active_share == 36 / 64 and s.overall.bsdf_efficiency == 28 / 64
    assert branch(s, "escaped").efficiency == 8 / 32 and branch(s, "light area").lanes == 24
    assert s.unrecorded == 2 / 64


def halves_scene(left, right):
    """A camera square on to a wall at z = 0 filling its view, of material `left` where x < 0 and
    `right` where x > 0: pixel columns left of the image's middle see the one, the others the
    other; light from the sky and an emitting sphere behind the camera."""
    b = SceneBuilder()
    quad = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    for x0, x1, m in ((-50.0, 0.0, left), (0.0, 50.0, right)):
        wall = np.array([[x0, -50, 0], [x1, -50, 0], [x1, 50, 0], [x0, 50, 0]], np.float32)
        b.add_mesh(Mesh(f"wall {x0}", wall, quad, None, b.material(m)))
    b.add_sphere((0, 0, 8), 1.0, emitter(2.0))
    camera = PerspectiveCamera([0, 0, 4], [0, 0, 0], [0, 1, 0], 60.0)
    return b.build("halves", camera=camera, environment=Environment.constant((0.2, 0.2, 0.2))).with_settings(
        max_depth=3, nee=True)


@pytest.mark.specialised       # the stats build is the scene's own program, with DIVERGENCE_STATS
def test_halves_of_two_materials_share_no_warp_where_warps_do_not_straddle_the_middle(backend):
    """Warps of 32 are 8x4 pixel tiles (8x8 work-groups): at width 32 the middle (column 16) falls
    between tiles, so every camera ray's warp shades one BSDF type; at width 20 it falls inside the
    tiles of columns 8-15, which shade both."""
    scene = halves_scene(diffuse(0.5), phong(0.3, 0.3, 20.0))
    s = divergence_stats(backend, scene, 32, 16, 2)
    first = s.per_iteration[0]
    assert first.distinct_bsdfs == 1 and first.bsdf_efficiency == first.active_share == 1
    # the flat wall is met by camera rays alone: half the warps (of 16, two samples) shade each side
    for name in ("bsdf diffuse", "bsdf phong"):
        assert (branch(s, name).executions, branch(s, name).lanes, branch(s, name).efficiency) == (16, 512, 1)
    straddling = divergence_stats(backend, scene, 20, 16, 2).per_iteration[0]
    # a row of groups holds 3 groups of 2 warps, the middle group's two mixed
    assert straddling.distinct_bsdfs == straddling.distinct_materials == (2 * 2 + 4 * 1) / 6
    assert straddling.active_share == 20 * 16 / (24 * 16)           # padding to whole groups of 8 columns
    # two diffuse materials: one BSDF's code, but the straddling warps shade two materials
    two = divergence_stats(backend, halves_scene(diffuse(0.5), diffuse(0.2)), 20, 16, 2).per_iteration[0]
    assert two.distinct_bsdfs == 1 and two.distinct_materials == (2 * 2 + 4 * 1) / 6


@pytest.mark.specialised
def test_one_diffuse_material_shades_one_type_where_every_active_lane_shades(backend):
    """Inside a closed diffuse sphere that emits, every ray meets the sphere and every path ends by
    Russian roulette after shading: each active lane shades the one BSDF, so its efficiency is the
    active share, iteration by iteration, and a warp shades one type."""
    b = SceneBuilder()
    b.add_sphere((0, 0, 0), 5.0, Material("diffuse", {"rho_d": 0.5}, emission=np.ones(3), twosided=True,
                                          emits_back=True))
    scene = b.build("inside", camera=PerspectiveCamera([0, 0, 1], [0, 0, 0], [0, 1, 0], 60.0),
                    environment=Environment.constant((0, 0, 0))).with_settings(max_depth=0, nee=True)
    s = divergence_stats(backend, scene, 16, 16, 2)
    assert len(s.per_iteration) > 5                 # Russian roulette lets paths go on past depth 5
    for it in [*s.per_iteration, s.overall]:
        assert it.distinct_bsdfs == 1 and it.bsdf_efficiency == pytest.approx(it.active_share, abs=1e-12)
        assert it.light_efficiency == pytest.approx(it.active_share, abs=1e-12)   # every shading samples a light
    assert {b.name for b in s.branches} == {"bsdf diffuse", "light area"}


@pytest.mark.specialised
def test_the_stats_build_renders_the_same_samples(backend):
    """The same image with the records as without (with the path queue: tests/test_path_sort.py)."""
    scene = halves_scene(diffuse(0.5), phong(0.3, 0.3, 20.0))
    r = Renderer(backend, scene, 24, 16)
    r.add_samples(2)
    plain = r.mean()
    arguments = r.kernels[True].get_info(cl.kernel_info.NUM_ARGS)
    (columns, rows), _ = r.launch_grid(16)
    size = 2 * 4 * len(FIELDS) * columns * rows
    records = cl.Buffer(backend.context, cl.mem_flags.READ_WRITE, size)
    cl.enqueue_fill_buffer(backend.queue, records, np.uint8(0), 0, size)
    r.record_shading(records, 4)
    assert r.kernels[True].get_info(cl.kernel_info.NUM_ARGS) == arguments + 1   # the records: the stats build's alone
    r.add_samples(2)
    assert np.array_equal(r.mean(), plain)          # the same paths, only recorded
    host = np.empty((2, 4, len(FIELDS), columns * rows), np.uint8)
    cl.enqueue_copy(backend.queue, host, records)
    assert np.count_nonzero(host[:, 0, SHADING]) == 2 * 24 * 16      # every pixel's camera ray, both samples


def test_the_stats_follow_the_path_tracer_alone(backend):
    scene = halves_scene(diffuse(0.5), diffuse(0.2)).with_settings(integrator="bdpt")
    with pytest.raises(UserError, match="halves: the divergence stats follow the path tracer .* not 'bdpt'"):
        divergence_stats(backend, scene, 16, 16, 1)


@pytest.mark.specialised
def test_bench_prints_the_table_and_writes_the_stats(tmp_path):
    out = tmp_path / "bench.json"
    r = in_process("bench", "--device", "cpu", "--no-cold", "--scenes", "cornell-box", "--estimator", "depth8+nee",
                  "--size", "16x16", "--spp", "2", "--divergence", "64", "--json", out)
    assert r.returncode == 0, r.stderr
    stats = json.loads(out.read_text())["results"][0]["divergence"]
    assert stats["warp"] == 64 and stats["paths"] == 16 * 16 * 2 and stats["iterations"] == 8
    assert stats["per_iteration"][0]["active_share"] == 1 and 0 < stats["overall"]["active_share"] < 1
    assert "divergence in warps of 64" in r.stdout and "bsdf diffuse" in r.stdout
    r = in_process("bench", "--device", "cpu", "--scenes", "cornell-box", "--divergence", "48")
    assert r.returncode == 2 and "a warp of 48 lanes" in r.stderr.strip().splitlines()[-1]
