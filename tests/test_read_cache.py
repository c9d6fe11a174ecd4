"""The cache of scenes read (pathtrace.scene.read_cache): a scene opened again comes from it, as
read the first time, with its warnings told again; a changed, gone or damaged file is read anew."""

import os
import shutil
import threading

import numpy as np
import pytest

import pathtrace.scene.meshes as meshes
import pathtrace.scene.read_cache as read_cache
from pathtrace.errors import UserError
from pathtrace.io import cache_files
from pathtrace.scene import load_scene, mesh_cache, obj
from tests.conftest import ROOT

SCENE = """<scene version="1.0.0">
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
  </sensor>
  <shape type="obj"><string name="filename" value="quad.obj"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
  <emitter type="constant"/>
</scene>
"""


@pytest.fixture
def scene_file(tmp_path, monkeypatch):
    """A Mitsuba scene of one OBJ mesh, whose version draws a warning; the cache on in a folder
    of its own, keeping every scene however fast it reads; and a count of the meshes parsed."""
    shutil.copy(ROOT / "tests/scenes/quad.obj", tmp_path / "quad.obj")
    (tmp_path / "s.xml").write_text(SCENE)
    monkeypatch.setenv("PATHTRACE_SCENE_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(read_cache, "MIN_SECONDS", 0.0)
    parsed = []
    parse = obj.parse_obj
    monkeypatch.setattr(obj, "parse_obj", lambda *args: (parsed.append(args), parse(*args))[1])
    return tmp_path / "s.xml", parsed


def load(path):
    """The scene, once the meshes kept beside its entry are written (a thread writes them)."""
    scene = load_scene(str(path))
    cache_files.wait_for_writes()
    return scene


def same(a, b) -> bool:
    return repr(a) == repr(b) and len(a.meshes) == len(b.meshes) and all(
        np.array_equal(m.vertices, n.vertices) and np.array_equal(m.faces, n.faces) for m, n in zip(a.meshes, b.meshes))


def test_a_scene_read_again_comes_from_the_cache_with_its_warnings(scene_file, capsys):
    path, parsed = scene_file
    first = load(path)
    warned = capsys.readouterr().err
    again = load(path)
    assert len(parsed) == 1 and same(first, again)
    assert "version 1.0.0" in warned and capsys.readouterr().err == warned


def test_a_scene_named_otherwise_says_the_name_it_is_given(scene_file, monkeypatch, capsys):
    """Read as s.xml from its folder, then by its absolute path from elsewhere: each scene
    says the name it was given (its source, its warnings), not the first one's."""
    path, _ = scene_file
    monkeypatch.chdir(path.parent)
    assert load_scene("s.xml").source == "s.xml"
    capsys.readouterr()
    monkeypatch.chdir(path.parent.parent)
    again = load(path)
    assert again.source == str(path) and f"{path}:1:" in capsys.readouterr().err


def test_a_changed_mesh_file_is_read_again(scene_file):
    path, parsed = scene_file
    first = load(path)
    mesh = path.parent / "quad.obj"
    mesh.write_text(mesh.read_text().replace("v 1", "v 2", 1))
    again = load(path)
    assert len(parsed) == 2 and not np.array_equal(first.meshes[0].vertices, again.meshes[0].vertices)


def edit(path, old, new):
    """Changes the scene file, its time of last change moved on by a second."""
    stat = path.stat()
    path.write_text(path.read_text().replace(old, new))
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))


def test_a_changed_scene_file_is_read_again_its_unchanged_obj_file_from_the_entry(scene_file):
    """The scene is read anew, and its OBJ file's mesh comes from the stale entry
    (pathtrace.scene.mesh_cache), as it was read the first time, for that read and the next."""
    path, parsed = scene_file
    first = load(path)
    edit(path, 'value="0.5"', 'value="0.25"')
    again = load(path)
    assert again.materials[0].params["rho_d"][0] == pytest.approx(0.25)
    assert len(parsed) == 1 and same(first, again)
    edit(path, 'value="0.25"', 'value="0.125"')
    assert load(path).materials[0].params["rho_d"][0] == pytest.approx(0.125) and len(parsed) == 1


def test_a_mesh_with_warnings_is_parsed_on_each_read_and_warns_each_time(scene_file, capsys):
    """A mesh whose check dropped a degenerate triangle is not kept with the entry: its warning,
    naming the scene's field, is told again when the changed scene is read."""
    path, parsed = scene_file
    mesh = path.parent / "quad.obj"
    mesh.write_text(mesh.read_text() + "f 1 1 2\n")
    load(path)
    assert "degenerate" in capsys.readouterr().err
    edit(path, 'value="0.5"', 'value="0.25"')
    load(path)
    assert len(parsed) == 2 and f"{path}:6:" in capsys.readouterr().err


def test_meshes_read_by_another_process_are_kept_with_the_entry(scene_file, monkeypatch):
    """A scene of many OBJ files, some read by another process (pathtrace.scene.mesh_processes):
    after a change of its file, every mesh comes from the entry and no process is started."""
    path, parsed = scene_file
    names = [f"quad{k}.obj" for k in range(6)]
    for name in names:
        shutil.copy(path.parent / "quad.obj", path.parent / name)
    shapes = "".join(f'<shape type="obj"><string name="filename" value="{n}"/></shape>' for n in names)
    path.write_text(SCENE.replace("</scene>", shapes + "</scene>"))
    monkeypatch.setattr(meshes.os, "sched_getaffinity", lambda _: {0, 1, 2, 3}, raising=False)
    monkeypatch.setattr(meshes.MeshFiles, "MANY", 2)
    monkeypatch.setattr(meshes.MeshFiles, "PROCESS_BYTES", 1)
    readings, read_in_processes = [], meshes.MeshFiles._read_in_processes
    monkeypatch.setattr(meshes.MeshFiles, "_read_in_processes",
                        lambda self, requests, n: (readings.append(requests), read_in_processes(self, requests, n)))
    first = load(path)
    assert readings and len(readings[0]) == 7
    edit(path, 'value="0.5"', 'value="0.25"')
    again = load(path)
    assert len(readings) == 1 and len(parsed) == 0 and same(first, again)


def test_a_damaged_entry_is_read_again_and_replaced(scene_file):
    """A damaged entry is a miss: the scene is read again (its mesh from the file kept beside the
    entry, while that is whole) and stored anew."""
    path, parsed = scene_file
    first = load(path)
    entry, = (path.parent / "cache").glob("*.scene")
    entry.write_bytes(entry.read_bytes()[:-10])
    assert same(load(path), first) and len(parsed) == 1
    kept, = (path.parent / "cache").glob("*.meshes")
    for damaged in (entry, kept):
        damaged.write_bytes(damaged.read_bytes()[:-10])
    assert same(load(path), first) and len(parsed) == 2
    assert same(load(path), first) and len(parsed) == 2


def test_a_file_that_shadows_a_built_in_name_is_read_as_the_file(scene_file, monkeypatch):
    """A built-in scene's entry is not used for a file of its name, which is taken as the file
    (and refused here: it has no scene format's suffix)."""
    path, _ = scene_file
    assert load_scene("simple").name == "simple"
    monkeypatch.chdir(path.parent)
    shutil.copy(path, path.parent / "simple")
    with pytest.raises(UserError):
        load_scene("simple")


def test_without_a_writable_folder_the_scene_is_still_read(scene_file, monkeypatch):
    path, parsed = scene_file
    blocker = path.parent / "blocker"
    blocker.write_text("")
    monkeypatch.setenv("PATHTRACE_SCENE_CACHE", str(blocker / "cache"))
    assert same(load(path), load(path)) and len(parsed) == 2


def test_reading_a_scene_imports_no_pyopencl(tmp_path):
    """A command reads its scene while the devices open in a thread that imports PyOpenCL
    (api.DevicesOpening): the reading, from its file and then from the cache, imports none of
    it, else it waits for that import (0.2 s of a warm start on the H200's host)."""
    import subprocess
    import sys
    code = ("import sys\nimport pathtrace.scene.read_cache as read_cache\nread_cache.MIN_SECONDS = 0\n"
            "from pathtrace.scene import load_scene\n"
            f"load_scene({str(ROOT / 'tests' / 'scenes' / 'cbox.pbrt')!r})\nprint('pyopencl' in sys.modules)\n")
    env = {**os.environ, "PATHTRACE_SCENE_CACHE": str(tmp_path)}
    for cached in (0, 1):
        assert len(list(tmp_path.glob("*.scene"))) == cached
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
        assert r.stdout.strip() == "False", (r.stdout, r.stderr)


def test_a_file_of_the_entry_gone_still_leaves_the_other_meshes_kept(scene_file):
    """An edit that removes a mesh and its file: the entry no longer holds, and the remaining
    OBJ file's mesh still comes from beside it."""
    path, parsed = scene_file
    shutil.copy(path.parent / "quad.obj", path.parent / "gone.obj")
    path.write_text(SCENE.replace("</scene>", '<shape type="obj"><string name="filename" value="gone.obj"/></shape></scene>'))
    load(path)
    (path.parent / "gone.obj").unlink()
    path.write_text(SCENE.replace('value="0.5"', 'value="0.25"'))
    assert len(load(path).meshes) == 1 and len(parsed) == 2


def test_meshes_larger_than_half_the_cache_are_not_kept(scene_file, monkeypatch):
    """A scene's meshes above half of MAX_BYTES would crowd out every other scene's: not written,
    and the other scenes' kept meshes stay."""
    path, parsed = scene_file
    monkeypatch.setattr(read_cache, "MAX_BYTES", 16 << 10)
    load(path)
    small, = (path.parent / "cache").glob("*.meshes")
    for k in range(200):
        shutil.copy(path.parent / "quad.obj", path.parent / f"q{k}.obj")
    shapes = "".join(f'<shape type="obj"><string name="filename" value="q{k}.obj"/></shape>' for k in range(200))
    (path.parent / "large.xml").write_text(SCENE.replace("</scene>", shapes + "</scene>"))
    load(path.parent / "large.xml")
    assert list((path.parent / "cache").glob("*.meshes")) == [small]


def test_a_write_begun_in_a_daemon_thread_is_waited_for_at_exit(tmp_path):
    """The viewer reads scenes in a daemon thread; the writes it begins are not daemons, which the
    interpreter would not wait for at its exit."""
    started = threading.Thread(target=cache_files.write_soon, args=(tmp_path / "e", [b"x"], "*", 1 << 20), daemon=True)
    started.start()
    started.join()
    writes = list(cache_files._writes)
    cache_files.wait_for_writes()
    assert writes and not any(w.daemon for w in writes) and (tmp_path / "e").is_file()


def test_a_mesh_found_in_one_reading_is_collected_by_every_reading_under_way():
    """Two scenes read at once (the viewer's thread and a notebook's, say): a mesh kept by one's
    entry and looked up by the other's reading is in both entries' meshes next time."""
    at, mesh = ("/a.obj", 1, 2), object()
    with mesh_cache.reading({at: mesh}) as first, mesh_cache.reading({}) as second:
        assert mesh_cache.holds(at) and mesh_cache.lookup(at) is mesh
        mesh_cache.collect(("/b.obj", 3, 4), mesh)
    assert set(first) == set(second) == {at, ("/b.obj", 3, 4)}
    assert not mesh_cache.holds(at)


def test_a_cache_variable_naming_a_file_is_said_once_and_the_render_goes_on(tmp_path, monkeypatch, capsys):
    """PATHTRACE_BVH_CACHE, PATHTRACE_SCENE_CACHE or PATHTRACE_CACHE naming a file was passed over
    without a word (a new user's run, 2026-12-03): one warning each, once."""
    from pathtrace.io import cache_files
    (tmp_path / "file").write_text("")
    monkeypatch.setattr(cache_files, "_warned_folders", set())
    for variable in ("PATHTRACE_BVH_CACHE", "PATHTRACE_SCENE_CACHE", "PATHTRACE_CACHE"):
        monkeypatch.setenv(variable, str(tmp_path / "file"))
    for _ in range(2):
        cache_files.chosen_folder("PATHTRACE_BVH_CACHE", "bvh")
        cache_files.chosen_folder("PATHTRACE_SCENE_CACHE", "scenes")
        cache_files.cache_dir()
    lines = capsys.readouterr().err.strip().splitlines()
    assert sorted(line.split(":")[2].strip() for line in lines) == ["PATHTRACE_BVH_CACHE", "PATHTRACE_CACHE",
                                                                     "PATHTRACE_SCENE_CACHE"], lines
    assert all(line.endswith("is not a folder; pathtrace keeps nothing there") for line in lines)
    monkeypatch.setenv("PATHTRACE_BVH_CACHE", "0")
    assert cache_files.chosen_folder("PATHTRACE_BVH_CACHE", "bvh") is None
