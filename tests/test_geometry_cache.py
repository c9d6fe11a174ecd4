"""The geometry cache: a scene compiled from its entry has the tree, rows and light table of one
compiled from its meshes, and gathers nothing; any change to what the rows are made from is a
new entry; a damaged, blocking or unwritable entry or folder costs a compile, never a wrong
scene; and a command leaving past the interpreter's teardown waits for an entry being written."""

import threading

import numpy as np
import pytest

import pathtrace.compiler.compiled as compiled_module
from pathtrace.cli import console
from pathtrace.compiler import bvh_cache, geometry_cache
from pathtrace.compiler.compiled import compile_scene
from pathtrace.io import cache_files
from pathtrace.scene.description import Mesh, SceneBuilder, diffuse, emitter
from pathtrace.shapes import Shape
from tests.test_bvh_cache import DAMAGES, damage_entry


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv("PATHTRACE_BVH_CACHE", str(tmp_path / "bvh"))
    return tmp_path / "bvh"


def grid(n, offset=0.0):
    """A bumpy (n - 1) x (n - 1) grid of 2 (n - 1)^2 triangles: vertices, faces, normals, uvs."""
    x, z = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    vertices = np.column_stack([x.ravel(), 0.1 * np.sin(5 * x * z).ravel() + offset, z.ravel()])
    i = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)).ravel()
    faces = np.concatenate([np.column_stack([i, i + n, i + 1]), np.column_stack([i + 1, i + n, i + n + 1])])
    normals = np.tile([0.0, 1.0, 0.0], (n * n, 1))
    uvs = np.column_stack([(x.ravel() + 1) / 2, (z.ravel() + 1) / 2])
    return vertices, faces, normals, uvs


def scene(change=None):
    """Two grids (one with normals and uvs, one emitting without them) and two lone spheres,
    bvh_cache.MIN_PRIMITIVES primitives and more; change(builder) adds or alters something."""
    b = SceneBuilder()
    v, f, n, uv = grid(66)
    b.add_mesh(Mesh("smooth", v, f, n, b.material(diffuse((0.6, 0.5, 0.4))), uvs=uv))
    v, f, _, _ = grid(66, offset=1.0)
    b.add_mesh(Mesh("lamp", v, f, None, b.material(emitter(2.0))))
    for k in range(2):
        b.add_sphere((k - 0.5, 0.3, 0), 0.2, b.material(diffuse(0.5)))
    if change:
        change(b)
    return b.build("grids")


def same(a, b):
    """Two CompiledScenes hold the same tree, buffers and light table."""
    assert np.array_equal(a.bvh.nodes.view(np.uint8), b.bvh.nodes.view(np.uint8))
    assert np.array_equal(a.bvh.order, b.bvh.order) and (a.bvh.depth, a.bvh.cost) == (b.bvh.depth, b.bvh.cost)
    for name, array in a.geometry_arrays().items():
        other = b.geometry_arrays()[name]
        assert array.dtype == other.dtype and np.array_equal(array.view(np.uint8), other.view(np.uint8)), name
    for name, array in a.material_arrays().items():
        assert np.array_equal(array, b.material_arrays()[name]), name
    assert (a.radius, a.lone_spheres, a.media_per_primitive) == (b.radius, b.lone_spheres, b.media_per_primitive)
    assert a.center.dtype == b.center.dtype and np.array_equal(a.center, b.center)
    assert np.array_equal(a.shape_prims, b.shape_prims)
    assert a.light_plan == b.light_plan


def no_gather(*args, **kwargs):
    raise AssertionError("gathered rows, where the geometry cache holds them")


def compiled_whole(s):
    c = compile_scene(s)
    cache_files.wait_for_writes()
    return c


def test_a_scene_compiled_again_reads_its_rows_and_gathers_nothing(folder, monkeypatch):
    s = scene()
    assert s.triangle_count + len(s.spheres) >= bvh_cache.MIN_PRIMITIVES
    built = compiled_whole(s)
    assert built.lone_spheres == 2 and len(built.lights.lights) > 8000 and built.uvs.shape[0] > 1
    entry, = folder.glob("*.geometry")
    for name in ("take_rows", "corner_table", "cached_bvh", "primitive_boxes"):
        monkeypatch.setattr(compiled_module, name, no_gather)
    progress = []
    again = compile_scene(s, progress=progress.append)
    same(again, built)
    assert progress == [1.0] and again.triangles.flags.writeable
    # before its tree, a scene held by the cache compiles the light plan of its entry
    ahead = compile_scene(s, tree=False)
    assert ahead.light_plan == built.light_plan and ahead.tree_ended is not None
    # and compile_before_devices has its tree with no device
    assert compiled_module.compile_before_devices(s).tree_ended is not None
    assert list(folder.glob("*.geometry")) == [entry]


@pytest.mark.parametrize("change", ["vertex", "material", "normals", "sphere", "medium"])
def test_what_the_rows_are_made_from_is_the_key(folder, change):
    from pathtrace.scene.media import MediumInterface

    def changed(b):
        mesh = b.meshes[0]
        if change == "vertex":
            mesh.vertices[7, 1] = np.nextafter(mesh.vertices[7, 1], np.float32(1))
        elif change == "material":
            mesh.material = b.meshes[1].material
        elif change == "normals":
            mesh.normals = None
        elif change == "sphere":
            b.spheres[1] = (*b.spheres[1][:3], 0.25)
        else:
            b.meshes[1].media = MediumInterface(-1, -1)
    path = geometry_cache.entry_path(compile_scene(scene(), tree=False))
    assert geometry_cache.entry_path(compile_scene(scene(), tree=False)) == path
    other = compile_scene(scene(changed), tree=False)
    assert geometry_cache.entry_path(other) != path
    compiled_whole(scene())
    other.build_tree()               # from its meshes, not from the first scene's entry
    same(other, compile_scene(scene(changed)))


def test_scenes_whose_rows_are_made_otherwise_are_not_kept(folder, monkeypatch):
    small = SceneBuilder()
    v, f, _, _ = grid(8)
    small.add_mesh(Mesh("small", v, f, None, small.material(diffuse(0.5))))
    with_shape = scene(lambda b: b.shapes.append(Shape("disk", "disk", (1.0, 0.0, 0.0, 2 * np.pi), np.eye(4), b.material(diffuse(0.5)))))
    for s in (small.build("small"), with_shape):
        compiled_whole(s)
    monkeypatch.setattr(geometry_cache, "MAX_BYTES", 4 << 20)       # the entry, 2.3 MB, is over half of it
    compiled_whole(scene())
    monkeypatch.setenv("PATHTRACE_BVH_CACHE", "0")
    compiled_whole(scene(lambda b: b.add_sphere((0, 2, 0), 0.1, 0)))
    assert not folder.exists() or not list(folder.glob("*.geometry"))


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_entry_is_compiled_again_and_replaced(folder, damage):
    s = scene()
    built = compiled_whole(s)
    entry, = folder.glob("*.geometry")
    damage_entry(entry, damage)
    assert geometry_cache.read_entry(entry) is None
    if damage == "fifo":
        entry.unlink()
    same(compiled_whole(s), built)
    assert geometry_cache.read_entry(entry) is not None


def test_an_unwritable_folder_still_compiles_and_leaves_nothing(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("PATHTRACE_BVH_CACHE", str(blocked / "bvh"))
    s = scene()
    first, second = compiled_whole(s), compiled_whole(s)
    same(first, second)
    assert [p.name for p in tmp_path.iterdir()] == ["file"]


def test_a_command_leaving_at_once_waits_for_an_entry_being_written(folder, monkeypatch):
    """console.run leaves past the interpreter's teardown where a build is under way; an entry
    being written then is written whole first, with no temporary file left."""
    started, release = threading.Event(), threading.Event()
    write = cache_files.write_entry

    def slow_write(*args):
        started.set()
        release.wait(5)
        return write(*args)
    monkeypatch.setattr(cache_files, "write_entry", slow_write)
    compile_scene(scene())
    assert started.wait(5) and not list(folder.glob("*.geometry"))
    threading.Timer(0.3, release.set).start()
    console._finish_cache_writes()
    assert sorted(p.suffix for p in folder.iterdir()) == [".bvh", ".geometry"]
    entry, = folder.glob("*.geometry")
    assert geometry_cache.read_entry(entry) is not None


def test_an_interrupt_ends_the_wait_for_an_entry(monkeypatch):
    """A second Ctrl-C while a command waits for an entry's write ends the wait, with no traceback:
    the user asked to stop (the write's temporary file is pruned later)."""
    def interrupted():
        raise KeyboardInterrupt
    monkeypatch.setattr(cache_files, "wait_for_writes", interrupted)
    console._finish_cache_writes()
