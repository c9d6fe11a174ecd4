"""`pathtrace bench --quick`: the benchmark runs end to end and reports consistent figures."""

import json
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from tests.commands import in_process


def fake_mitsuba(tmp_path):
    """A Python whose Mitsuba 3 sets its variant and nothing more: the bench's check of the Python
    passes, and a render with it fails."""
    (tmp_path / "fake" / "mitsuba").mkdir(parents=True)
    (tmp_path / "fake" / "mitsuba" / "__init__.py").write_text("def set_variant(variant):\n    pass\n")
    python = tmp_path / "python"
    python.write_text(f'#!/bin/sh\nPYTHONPATH="{tmp_path / "fake"}" exec "{sys.executable}" "$@"\n')
    python.chmod(0o755)
    return python


def test_quick_bench_writes_a_table_and_json(tmp_path):
    """A sphere scene and the textured mesh scene, both estimators: each (scene, estimator) one row
    (every target scene would cost the suite half a minute of kernel builds)."""
    out = tmp_path / "bench.json"
    r = in_process("bench", "--quick", "--device", "cpu", "--json", out, "--scenes", "simple", "teapot-textured",
                  "--estimator", "rr", "--estimator", "depth8+nee")
    assert r.returncode == 0, r.stderr
    data = json.loads(out.read_text())
    rows = data["results"]
    assert len(rows) == 2 * 2 and {row["estimator"] for row in rows} == {"rr", "depth8+nee"}
    assert {row["scene"] for row in rows} == {"simple", "teapot-textured"}
    for row in rows:
        assert row["width"] == 320 and row["height"] == 180 and row["spp"] == 8
        assert row["seconds"] > 0 and row["bvh_seconds"] < row["seconds"]
        assert abs(row["msamples_per_s"] - 320 * 180 * 8 / row["seconds"] / 1e6) < 1e-6 * row["msamples_per_s"] + 1e-9
        assert row["mrays_per_s"] >= row["msamples_per_s"]      # at least the camera ray
        assert row["build_warm_seconds"] >= 0
    assert "simple" in r.stdout and "Msamples/s" in r.stdout


def test_bench_rejects_bad_input(tmp_path):
    r = in_process("bench", "--quick", "--scenes", "nosuch")
    assert r.returncode == 1 and "neither a scene file nor a built-in scene" in r.stderr
    r = in_process("bench", "--quick", "--estimator", "fast")
    assert r.returncode == 1 and "--estimator: unknown 'fast'" in r.stderr
    r = in_process("bench", "--quick", "--json", tmp_path / "no" / "b.json")
    assert r.returncode == 1 and "does not exist" in r.stderr


def test_build_bench_times_spheres_and_triangles(tmp_path):
    out = tmp_path / "builds.json"
    r = in_process("bench", "--builds", "2k", "20k", "--device", "cpu", "--json", out)
    assert r.returncode == 0, r.stderr
    rows = json.loads(out.read_text())["results"]
    assert [row["scene"] for row in rows] == ["spheres2k-diffuse", "heightfield2k", "spheres20k-diffuse", "heightfield20k"]
    for row in rows:
        assert row["seconds"] > 0 and row["sah_cost"] > 0.5
        assert 0 < row["nodes"] < row["primitives"] and row["node_megabytes"] == row["nodes"] * 128 / 2**20
    assert rows[0]["primitives"] == 2000 and abs(rows[3]["primitives"] - 20000) < 400   # a square grid, and its ball
    assert "build s" in r.stdout and "heightfield20k" in r.stdout
    r = in_process("bench", "--builds", "1")
    assert r.returncode == 2 and "'1' is not a count from 2 to 100M" in r.stderr


def test_display_and_denoise_timings(tmp_path):
    out = tmp_path / "timings.json"
    r = in_process("bench", "--display", "--denoise", "--size", "64x36", "--device", "cpu", "--json", out)
    assert r.returncode == 0, r.stderr
    rows = json.loads(out.read_text())["results"]
    steps = [row["what"] for row in rows]
    assert steps[:2] == ["display: sums (default)", "display: half"]     # PoCL shares the host's memory
    assert [s for s in steps if s.startswith("denoise")] == ["denoise, high", "denoise, balanced", "denoise, fast"]
    assert all(row["milliseconds"] > 0 and (row["width"], row["height"]) == (64, 36) for row in rows)


def test_load_bench_scenes_say_the_same_in_each_format(tmp_path):
    """The load rows' scenes, as pathtrace's file and as the Mitsuba 3 XML timed against it,
    are one scene: the same triangles, camera and film, and images equal to within noise."""
    import numpy as np

    from pathtrace import api
    from pathtrace.bench.load import write_height_field, write_meshes
    for ours, xml, what, size in (write_meshes(tmp_path, 6), write_height_field(tmp_path)):
        a, b = api.load(tmp_path / ours), api.load(tmp_path / xml)
        assert sum(len(m.faces) for m in a.meshes) == sum(len(m.faces) for m in b.meshes) == int(what.split()[3].replace(",", ""))
        assert (a.settings.width, a.settings.height) == (b.settings.width, b.settings.height) == size
        assert np.allclose(a.camera.eye, b.camera.eye) and abs(a.camera.vfov - b.camera.vfov) < 1e-4
        if len(a.meshes) > 1:            # the height field's million triangles are for the timing
            ia, ib = (api.render(s, device="cpu", spp=64, seed=int(s is b)) for s in (a, b))
            assert abs(ia.mean() - ib.mean()) < 0.02 * ia.mean(), (ia.mean(), ib.mean())



def test_the_obj_scene_is_meshes850_as_obj_files(tmp_path):
    """bench_scenes.write_obj_meshes (the OBJ scene for `bench --load --load-scene`) holds
    meshes850's tori at the same places, as OBJ files in Mitsuba XML."""
    import numpy as np

    from pathtrace import api
    from pathtrace.bench.scenes import write_meshes, write_obj_meshes
    ply = api.load(tmp_path / write_meshes(tmp_path, 5)[0])
    obj = api.load(write_obj_meshes(tmp_path, 5))
    assert [len(m.faces) for m in obj.meshes] == [len(m.faces) for m in ply.meshes] == [1024] * 5
    for a, b in zip(obj.meshes, ply.meshes):
        assert np.allclose(a.vertices.min(axis=0), b.vertices.min(axis=0), atol=1e-5)
        assert np.allclose(a.vertices.max(axis=0), b.vertices.max(axis=0), atol=1e-5)
        assert a.uvs is not None and a.normals is not None

def test_load_bench_rows(tmp_path):
    """`bench --load`: a row per generated scene (those --scenes names) and per --load-scene file, with pathtrace's
    seconds, the scene read and its BVH built, and both from their caches; Mitsuba's column only when asked for, and
    a Python without Mitsuba is one line."""
    scene = tmp_path / "one.toml"
    scene.write_text('[[spheres]]\ncenter = [0, 0, -3]\nradius = 1\nmaterial = { type = "diffuse", rho_d = 0.5 }\n')
    out = tmp_path / "load.json"
    r = in_process("bench", "--load", "--scenes", "meshes850", "--repeats", "1", "--device", "cpu",
                  "--load-scene", scene, "--json", out)
    assert r.returncode == 0, r.stderr
    rows = json.loads(out.read_text())["results"]
    assert [row["scene"] for row in rows] == ["meshes850", "one"]
    assert all(row["seconds"] > 0 and row["cached_seconds"] > 0 and row["mitsuba_seconds"] is None
               and row["device"] == "cpu" for row in rows)
    assert "pathtrace s" in r.stdout and "cached s" in r.stdout and "870,400 triangles" in r.stdout
    r = in_process("bench", "--load", "--scenes", "meshes85", "--device", "cpu")
    assert r.returncode == 1 and r.stderr.strip().splitlines() == [
        "pathtrace: error: --scenes: with --load, 'meshes85' is not a generated row (one of heightfield1M, "
        "meshes850); did you mean meshes850?"], r.stderr
    r = in_process("bench", "--load-scene", tmp_path / "missing.toml", "--repeats", "1", "--device", "cpu")
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1 and "missing.toml" in r.stderr
    r = in_process("bench", "--load-scene", scene, "--repeats", "1", "--device", "cpu",
                  "--mitsuba", sys.executable, "--mitsuba-variant", "scalar_rgb")
    assert r.returncode == 1 and "No module named 'mitsuba'" in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and not r.stdout    # before any timed run


@pytest.mark.specialised     # the counts of the scenes' own programs
def test_bench_without_the_cold_build_and_with_traversal_counts_and_the_trace_split(tmp_path):
    out = tmp_path / "bench.json"
    media = str(Path(__file__).parent / "scenes" / "media-fog.xml")
    r = in_process("bench", "--quick", "--device", "cpu", "--scenes", "simple", media, "--no-cold", "--traversal",
                  "--trace-split", "--json", out)
    assert r.returncode == 0, r.stderr
    row, fog = json.loads(out.read_text())["results"]
    assert row["build_cold_seconds"] is None and row["seconds"] > 0
    assert " -/" in r.stdout
    # simple's five spheres have no tree: every ray tests all five (app/device/features.py: FLAT_MAX)
    assert row["nodes_per_ray"] == 0 and row["primitives_per_ray"] == 5 and row["rays_per_sample"] >= 1
    assert "traversal: " in r.stdout
    split = row["trace_split"]
    assert split["rays_per_pixel"]["camera"] == 1 and split["megakernel_ms"] > 0 and "trace split (depth 2" in r.stdout
    # a scene the split's kernels do not follow gets a line saying so, and the bench goes on
    assert fog["trace_split"] is None and "media-fog has participating media" in r.stdout


def test_bench_renders_the_generated_textured_scene_and_asks_mitsuba(tmp_path):
    """`tori400-textured` is written on demand and rendered; --mitsuba then runs the Python
    given, whose failure (here: a Mitsuba that cannot load a scene) is one line after
    pathtrace's row."""
    r = in_process("bench", "--device", "cpu", "--no-cold", "--scenes", "tori400-textured", "--size", "32x18",
                  "--spp", "1", "--mitsuba", fake_mitsuba(tmp_path))
    assert r.returncode == 1, r.stderr
    assert "tori400-textured" in r.stdout and "depth8+nee" in r.stdout
    assert len(r.stderr.strip().splitlines()) == 1 and "tori400-textured.xml" in r.stderr, r.stderr


def test_the_generated_scene_of_seven_materials(tmp_path):
    """`tori400-materials` is the textured tori under seven BSDF types in turn, each torus with
    its own image where its material takes one; pathtrace reads them all as those types."""
    from pathtrace.bench.report import scene_file
    from pathtrace.scene import load_scene
    from pathtrace.textures.texture import Texture
    table = load_scene(scene_file("tori400-materials", tmp_path, (32, 18))).materials
    materials = [table.get(k) for k in range(len(table))]
    assert {m.type for m in materials} == {"diffuse", "roughplastic", "plastic", "roughconductor", "conductor",
                                           "roughdielectric", "dielectric"}
    # 400 tori, the k-th under the (k mod 7)-th material: 58 diffuse, 57 of each plastic, each
    # with its image, and the ground's diffuse with the checkerboard's
    textured = [m for m in materials if any(isinstance(v, Texture) for v in m.params.values())]
    assert len(textured) == 58 + 57 + 57 + 1, len(textured)


def test_bench_mitsuba_column_without_a_twin_or_a_python(tmp_path):
    """A scene a twin cannot say (simple's Phong spheres) gets a line saying so and the bench goes
    on; a Python that is not there is one error line."""
    r = in_process("bench", "--quick", "--device", "cpu", "--no-cold", "--scenes", "simple", "--estimator",
                  "depth8+nee", "--mitsuba", fake_mitsuba(tmp_path))
    assert r.returncode == 0, r.stderr
    assert "Mitsuba 3: no twin of simple" in r.stdout and "(phong)" in r.stdout
    r = in_process("bench", "--quick", "--device", "cpu", "--no-cold", "--scenes", "simple-diffuse", "--estimator",
                  "depth8+nee", "--mitsuba", tmp_path / "no-python")
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1
    assert "cannot run" in r.stderr and "no-python" in r.stderr


def test_bench_rounds_count_the_medians_of_both_renderers(tmp_path):
    """--rounds 3: each row's render timed three times, and Mitsuba's (here a stand-in that
    records its renders, tests/test_mitsuba_timing.py) too; the medians are compared."""
    from statistics import median
    from tests.test_mitsuba_timing import fake_mitsuba as fake_packages
    fake_packages(tmp_path)
    python = tmp_path / "python"
    python.write_text(f'#!/bin/sh\nPYTHONPATH="{tmp_path}" RENDERS="{tmp_path / "renders.jsonl"}" '
                      f'exec "{sys.executable}" "$@"\n')
    python.chmod(0o755)
    out = tmp_path / "bench.json"
    r = in_process("bench", "--quick", "--device", "cpu", "--no-cold", "--scenes", "simple-diffuse", "--estimator",
                  "depth8+nee", "--rounds", "3", "--mitsuba", python, "--mitsuba-variant", "scalar_rgb",
                  "--json", out)
    assert r.returncode == 0, r.stderr
    row, = json.loads(out.read_text())["results"]
    assert len(row["render_rounds"]) == 3 and row["render_seconds"] == median(row["render_rounds"])
    assert row["seconds"] >= row["render_seconds"]
    assert len(row["mitsuba_rounds"]) == 3 and row["mitsuba_seconds"] == median(row["mitsuba_rounds"])
    assert len((tmp_path / "renders.jsonl").read_text().splitlines()) == 4     # one untimed, three timed
    assert "(medians of 3 renders)" in r.stdout
    r = in_process("bench", "--quick", "--rounds", "0")
    assert r.returncode == 2 and "--rounds" in r.stderr


def test_no_cold_builds_nothing_the_cache_does_not_hold(backend, monkeypatch):
    """`--no-cold` skips the every-feature program's build without the cache (a minute of register
    trials on NVIDIA): where the cache does not hold it either, the warm time is not measured
    (building it to fill the cache is that very build), and no build is made."""
    import pathtrace.bench.report as report
    built = []
    monkeypatch.setattr(report, "build_program", lambda *a, **k: built.append(k) or SimpleNamespace(seconds=0.25))
    monkeypatch.setattr(report, "built_before", lambda device, entry: False)
    assert report.kernel_build_times(backend, cold=False) == (None, None) and not built
    monkeypatch.setattr(report, "built_before", lambda device, entry: True)
    assert report.kernel_build_times(backend, cold=False) == (None, 0.25) and len(built) == 1
    assert report.kernel_build_times(backend, cold=True) == (0.25, 0.25) and built[1] == {"use_cache": False}


@pytest.mark.parametrize("args,message", [
    (["--first-image", "--load"], "--first-image and --load time different things"),
    (["--load", "--builds"], "--load and --builds time different things"),
    (["--builds", "--denoise"], "--builds and --display or --denoise time different things"),
    (["--load", "--size", "160x90"], "--size: bench --load times each scene's loading at 64x64"),
    (["--load-scene", "x.toml", "--size", "160x90"], "--size: bench --load"),
])
def test_bench_modes_one_at_a_time_and_without_unused_options(args, message):
    """bench's modes each print a table of their own: two at once, or --size given to --load,
    which renders at 64x64 whatever it is told, is one line before any timed run (a helper's run
    had --first-image --load time the first images alone, and --load take --size silently)."""
    r = in_process("bench", *args)
    assert r.returncode == 1 and message in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr
