"""`pathtrace bench --first-image` (app/bench/first_image.py): command to first image, cold and warm."""

import json
import sys
from pathlib import Path

import pytest

from pathtrace.errors import UserError
from tests.commands import in_process

# Mitsuba's load measurement (pathtrace.bench.mitsuba_timing.LOAD) against a stand-in that writes its
# image and records, per run, whether Dr.Jit's kernel cache (~/.drjit) was there already.
FAKE_MITSUBA = """
import json, os
def set_variant(variant): pass
def load_file(path): return path
def render(scene, spp=1): return scene
class Bitmap:
    def __init__(self, image): pass
    def write(self, path):
        cache = os.path.join(os.environ["HOME"], ".drjit")
        with open(os.environ["RUNS"], "a") as f:
            f.write(json.dumps({"home": os.environ["HOME"], "cached": os.path.isdir(cache)}) + "\\n")
        os.makedirs(cache, exist_ok=True)
        with open(path, "w") as f:
            f.write("image")
"""


def fake_mitsuba(tmp_path) -> Path:
    (tmp_path / "fake" / "mitsuba").mkdir(parents=True)
    (tmp_path / "fake" / "mitsuba" / "__init__.py").write_text(FAKE_MITSUBA)
    python = tmp_path / "python"
    python.write_text(f'#!/bin/sh\nPYTHONPATH="{tmp_path / "fake"}" RUNS="{tmp_path / "runs.jsonl"}" '
                      f'exec "{sys.executable}" "$@"\n')
    python.chmod(0o755)
    return python


def first_image_row(tmp_path, scene: str, size: str, repeats: int, *options) -> tuple:
    """`bench --first-image` of one scene on the CPU: (its one row from the JSON, the command's result)."""
    out = tmp_path / "first.json"
    r = in_process("bench", "--first-image", "--scenes", scene, "--size", size, "--repeats", str(repeats),
                   "--device", "cpu", *options, "--json", out)
    assert r.returncode == 0, r.stderr
    row, = json.loads(out.read_text())["results"]
    return row, r


def with_mitsuba(tmp_path) -> tuple:
    """The options that time a stand-in Mitsuba (fake_mitsuba) beside each row."""
    return "--mitsuba", fake_mitsuba(tmp_path), "--mitsuba-variant", "scalar_rgb"


def test_a_row_is_timed_cold_from_empty_caches_then_warm(tmp_path):
    row, r = first_image_row(tmp_path, "simple", "16x9", 1)
    assert (row["scene"], row["what"], row["device"], row["width"], row["height"]) == ("simple", "built-in", "cpu", 16, 9)
    assert row["cold_seconds"] > 0 and row["warm_seconds"] > 0
    # the cold run's caches were empty before it, and it filled them (PoCL's programs here)
    assert row["cache_files_before"] == 0 and row["cache_files_after"] > 0
    assert row["mitsuba_cold_seconds"] is None and row["mitsuba_warm_seconds"] is None
    assert row["edited_seconds"] is None            # a built-in scene has no file to edit
    header, line = r.stdout.splitlines()
    assert "cold s" in header and "warm s" in header and "edited s" in header and line.startswith("simple ")


def test_the_obj_scene_is_a_row_bench_writes(tmp_path):
    """`meshes850-obj` (#55's "several hundred OBJ meshes"): 850 OBJ files bench writes, each
    read from its file cold, the scene from its cache warm, and again after its file changed;
    its XML's film is the rows' size, so that Mitsuba renders it beside (here a stand-in)."""
    row, r = first_image_row(tmp_path, "meshes850-obj", "16x9", 1, *with_mitsuba(tmp_path))
    assert (row["scene"], row["what"]) == ("meshes850-obj", "written by bench")
    assert row["cold_seconds"] > row["warm_seconds"] > 0 and row["cache_files_after"] > 0
    assert row["edited_seconds"] > 0
    assert row["mitsuba_cold_seconds"] > 0, r.stdout


def test_mitsuba_is_timed_cold_in_a_fresh_home_then_warm(tmp_path, monkeypatch):
    """The row's Mitsuba runs: each cold one finds no kernel cache, the warm ones find the one the
    last cold run left; the cold figures are the medians of their runs, and the ratios are printed.
    pathtrace's own runs build the scene's program, which PoCL builds cold in a few seconds, where
    the generic program takes several times that."""
    import statistics
    monkeypatch.setenv("PATHTRACE_PROGRAM", "specialised")
    row, r = first_image_row(tmp_path, "cornell-box", "16x16", 2, *with_mitsuba(tmp_path))
    assert row["mitsuba_variant"] == "scalar_rgb" and row["mitsuba_cold_seconds"] > 0 and row["mitsuba_warm_seconds"] > 0
    runs = [json.loads(line) for line in (tmp_path / "runs.jsonl").read_text().splitlines()]
    assert [run["cached"] for run in runs] == [False, False, True, True] and len({run["home"] for run in runs}) == 1
    for who in ("", "mitsuba_"):
        assert len(row[f"{who}cold_runs"]) == 2 and row[f"{who}cold_seconds"] == statistics.median(row[f"{who}cold_runs"])
    # pathtrace's cold runs each built the program (PoCL's cache emptied before each): slower than the warm one
    assert min(row["cold_runs"]) > row["warm_seconds"]
    assert not Path(runs[0]["home"]).exists()          # removed with the bench's folder
    assert "(scalar_rgb)" in r.stdout


def test_no_mitsuba_column_without_an_xml_of_the_rows_size(tmp_path):
    """A scene a twin cannot say, and an XML file whose film is another size, get a reason."""
    from pathtrace.bench.first_image import FirstImage, time_mitsuba
    row = lambda name: FirstImage(name, "", "cpu", 64, 64, 1.0, 1.0, "", 0, 1)   # noqa: E731
    fog = str(Path(__file__).parent / "scenes" / "media-fog.xml")
    assert time_mitsuba(row("simple"), "simple", tmp_path / "a", sys.executable, "scalar_rgb", 1) \
        .startswith("no twin of simple:")
    assert time_mitsuba(row("media-fog"), fog, tmp_path / "b", sys.executable, "scalar_rgb", 1) \
        == "media-fog.xml has a 64x40 film, which Mitsuba renders as it is; --size 64x40 compares it"


def test_a_failed_render_or_a_missing_image_is_one_line_naming_the_command(tmp_path):
    r = in_process("bench", "--first-image", "--scenes", "simple", "--size", "16x9", "--repeats", "1",
                  "--device", "nosuch")
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "-m pathtrace render simple --size 16x9 ... failed: " in r.stderr and "nosuch" in r.stderr
    from pathtrace.bench.load import best_time
    with pytest.raises(UserError, match=r"-c \.\.\. exited 0 but wrote no out\.exr$"):
        best_time([sys.executable, "-c", "pass"], 1, tmp_path, output=tmp_path / "out.exr")


def test_the_timed_processes_read_the_packages_bytecode(tmp_path, monkeypatch):
    """Before timing, bench writes the bytecode of the package and of the packages a render
    imports (an installation holds it), so that a timed start reads it rather than compiles every
    module, even where PYTHONDONTWRITEBYTECODE keeps the timed processes from writing it (a lent
    machine's NumPy, installed without its bytecode, took 0.36 s of every start there)."""
    import importlib.util
    import pathtrace.api
    from pathtrace.bench import load
    cached = Path(importlib.util.cache_from_source(pathtrace.api.__file__))
    cached.unlink(missing_ok=True)
    package = tmp_path / "a_render_import"
    package.mkdir()
    (package / "__init__.py").write_text("VALUE = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(load, "RENDER_IMPORTS", ("a_render_import", "not_installed_anywhere"))
    load.cache_bytecode()
    assert cached.is_file() and cached.stat().st_size > 0
    assert Path(importlib.util.cache_from_source(str(package / "__init__.py"))).is_file()


def test_a_file_named_among_the_scenes_is_a_files_row(tmp_path):
    """A scene file given to --scenes, as to --load-scene, is labelled by its path's end, not as a
    built-in scene (a reviewer's run found it called "built-in", its whole path as its name)."""
    from pathtrace.bench.first_image import rows
    xml = Path(__file__).parent / "scenes" / "cbox.xml"
    found = rows(tmp_path, ["simple", str(xml)], [], (16, 9))
    assert [(name, what) for name, _, what in found] == [("simple", "built-in"), ("cbox", "tests/scenes/cbox.xml")]
    assert found[1][1] == str(xml.resolve())
