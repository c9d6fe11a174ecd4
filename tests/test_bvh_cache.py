"""The BVH cache: a tree read back is the tree built, is read rather than built, and a damaged,
foreign, blocking or unwritable entry or folder costs a build, never a wrong tree or a hang."""

import os
import subprocess
import sys
import time

import numpy as np
import pytest

import pathtrace.compiler.bvh_cache as cache
from pathtrace.io import cache_files
from pathtrace.compiler.bvh import build_bvh
from tests.conftest import ROOT

N = cache.MIN_PRIMITIVES


def boxes(seed=0, n=N):
    lo = np.random.default_rng(seed).random((n, 3), dtype=np.float32) * 10
    return lo, lo + 0.05


def same(a, b):
    return (np.array_equal(a.nodes.view(np.uint8), b.nodes.view(np.uint8)) and np.array_equal(a.order, b.order)
            and a.depth == b.depth and a.cost == b.cost)


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv("PATHTRACE_BVH_CACHE", str(tmp_path / "bvh"))
    return tmp_path / "bvh"


def no_build(*args):
    raise AssertionError("built, where the cache holds the tree")


def test_a_tree_is_read_back_as_built_and_not_built_again(folder, monkeypatch):
    lo, hi = boxes()
    built = cache.cached_bvh(lo, hi, N // 2)
    assert same(built, build_bvh(lo, hi, N // 2))
    entry, = folder.glob("*.bvh")
    monkeypatch.setattr(cache, "build_bvh", no_build)
    progress = []
    read = cache.cached_bvh(lo, hi, N // 2, progress=progress.append)
    assert same(read, built) and read.nodes.flags.writeable and progress == [1.0]


def test_the_key_is_the_boxes_and_the_spheres_count(folder):
    lo, hi = boxes()
    cache.cached_bvh(lo, hi, 0)
    cache.cached_bvh(lo, hi, N)            # the same boxes, the kinds split elsewhere
    moved = lo.copy()
    moved[7, 1] = np.nextafter(moved[7, 1], np.float32(0))
    cache.cached_bvh(moved, hi, 0)         # one float's last bit
    assert len(list(folder.glob("*.bvh"))) == 3


def test_small_scenes_and_a_cache_turned_off_write_nothing(folder, monkeypatch):
    lo, hi = boxes(n=N - 1)
    cache.cached_bvh(lo, hi)
    assert not folder.exists()
    monkeypatch.setenv("PATHTRACE_BVH_CACHE", "0")
    cache.cached_bvh(*boxes())
    assert not folder.exists()


DAMAGES = ["truncated", "flipped", "empty", "fifo"]


def damage_entry(entry, damage: str):
    """Replaces a cache entry by a damaged one: cut in half, one bit flipped, empty, or a FIFO,
    which would block a reader that opened it."""
    data = entry.read_bytes()
    entry.unlink()
    if damage == "truncated":
        entry.write_bytes(data[: len(data) // 2])
    elif damage == "flipped":
        entry.write_bytes(data[:1000] + bytes([data[1000] ^ 1]) + data[1001:])
    elif damage == "empty":
        entry.write_bytes(b"")
    else:
        os.mkfifo(entry)


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_entry_is_built_again_and_replaced(folder, damage):
    lo, hi = boxes()
    built = cache.cached_bvh(lo, hi)
    entry, = folder.glob("*.bvh")
    damage_entry(entry, damage)
    assert cache.read_entry(entry, N) is None
    if damage == "fifo":
        entry.unlink()
    assert same(cache.cached_bvh(lo, hi), built)
    assert cache.read_entry(entry, N) is not None


def test_an_unwritable_folder_still_builds_and_leaves_nothing(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("PATHTRACE_BVH_CACHE", str(blocked / "bvh"))
    lo, hi = boxes()
    assert same(cache.cached_bvh(lo, hi), build_bvh(lo, hi))
    assert [p.name for p in tmp_path.iterdir()] == ["file"]


def test_the_least_recently_used_entries_go_first(folder):
    for seed in range(3):
        cache.cached_bvh(*boxes(seed))
    entries = sorted(folder.glob("*.bvh"), key=lambda p: p.stat().st_mtime)
    for age, entry in enumerate(entries):
        os.utime(entry, (1000 + age, 1000 + age))
    cache.read_entry(entries[0], N)        # used: now the newest
    cache_files.prune(folder, "*.bvh", entries[0].stat().st_size + entries[2].stat().st_size)
    assert sorted(p.name for p in folder.glob("*.bvh")) == sorted(p.name for p in (entries[0], entries[2]))


def test_writers_of_one_entry_at_once_each_write_a_file_of_their_own(tmp_path):
    """Threads writing one entry at once (a scene compiled twice while its geometry's first write
    goes on) each write a temporary file of their own, renamed whole over the entry: the entry is
    one writer's payload, and no temporary file is left."""
    import threading
    payloads = [bytes([k]) * (1 << 22) for k in range(4)]
    done = []
    threads = [threading.Thread(target=lambda p=p: done.append(cache_files.write_entry(tmp_path / "e.bvh", p)))
               for p in payloads]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert done == [True] * 4 and bytes(cache_files.read_entry(tmp_path / "e.bvh")) in payloads
    assert [p.name for p in tmp_path.iterdir()] == ["e.bvh"]


def test_a_write_cut_short_leaves_a_file_that_a_later_prune_removes(tmp_path):
    """A process killed as it wrote (or leaving at an interrupt) leaves its temporary file: a
    prune removes it once it has been unchanged for STALE_SECONDS, and not before (it may be a
    write under way)."""
    stale, fresh = tmp_path / f"a.bvh.x1{cache_files.TEMPORARY}", tmp_path / f"b.bvh.x2{cache_files.TEMPORARY}"
    for f in (stale, fresh):
        f.write_bytes(b"half")
    old = time.time() - cache_files.STALE_SECONDS - 5
    os.utime(stale, (old, old))
    cache_files.prune(tmp_path, "*.bvh", 1 << 30)
    assert [p.name for p in tmp_path.iterdir()] == [fresh.name]


def test_a_mesh_renders_the_same_from_the_cache(tmp_path):
    """From the command: the first render stores its scene's tree, the second reads it (its
    folder's entry is the only one, and unchanged) and writes the same image."""
    n = 190
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    z = 0.1 * np.sin(4 * x) * np.cos(3 * y)
    vertices = np.column_stack([x.ravel(), z.ravel(), y.ravel()])
    i = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)).ravel()
    faces = np.concatenate([np.column_stack([i, i + n, i + 1]), np.column_stack([i + 1, i + n, i + n + 1])])
    assert len(faces) >= N
    obj = tmp_path / "field.obj"
    obj.write_text("".join(f"v {a} {b} {c}\n" for a, b, c in vertices)
                   + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces))
    scene = tmp_path / "scene.toml"
    scene.write_text('[camera]\neye = [0, 2, 2.5]\nlook_at = [0, 0, 0]\n\n[[meshes]]\nfile = "field.obj"\n'
                     'material = { type = "diffuse", rho_d = 0.6 }\n')
    env = {**os.environ, "PATHTRACE_BVH_CACHE": str(tmp_path / "bvh")}
    images = []
    for k in range(2):
        out = tmp_path / f"out{k}.exr"
        r = subprocess.run([sys.executable, "-m", "pathtrace", "render", scene, "--size", "32x24", "--spp", "2",
                            "--device", "cpu", "-o", out, "-q"], cwd=ROOT, env=env, capture_output=True, text=True,
                           timeout=300)
        assert r.returncode == 0, r.stderr
        entry, = (tmp_path / "bvh").glob("*.bvh")
        images.append((out.read_bytes(), entry.read_bytes()))
    assert images[0] == images[1]


def test_a_scene_builds_its_tree_before_a_device_only_where_the_cache_holds_it(folder, monkeypatch):
    """build_tree(cached_only=True), which a command calls while its devices open (api.prepare):
    on a miss it builds nothing and leaves the tree to a device's build; on a hit it reads the
    tree without a device, and the scene's tables are those of a scene compiled whole."""
    from pathtrace.compiler import compiled as compiled_module
    from pathtrace.scene import load_scene
    scene = load_scene("spheres64k")
    first = compiled_module.compile_scene(scene, None, tree=False)
    monkeypatch.setattr(cache, "build_bvh", no_build)
    assert first.build_tree(cached_only=True) is False
    assert first.bvh is None and first.tree_ended is None and not folder.exists()
    monkeypatch.undo()
    monkeypatch.setenv("PATHTRACE_BVH_CACHE", str(folder))
    whole = compiled_module.compile_scene(scene)         # builds the tree, and keeps it
    assert first.build_tree() and same(first.bvh, whole.bvh)
    monkeypatch.setattr(cache, "build_bvh", no_build)
    again = compiled_module.compile_scene(scene, None, tree=False)
    assert again.build_tree(cached_only=True) is True and again.tree_ended is not None
    for name, array in whole.geometry_arrays().items():
        assert np.array_equal(again.geometry_arrays()[name], array), name


def test_large_gathers_work_in_a_forked_child():
    """take_rows gathers in threads of its own: a child forked after a parent's gathers (a
    farm's or a user's worker) gathers too, where a pool made in the parent would hang it."""
    import multiprocessing

    from pathtrace.compiler.compiled import GATHER_SPLIT, take_rows
    values = np.arange(4 * GATHER_SPLIT, dtype=np.float32).reshape(-1, 4)
    indices = np.random.default_rng(1).permutation(GATHER_SPLIT)
    assert np.array_equal(take_rows(values, indices), values[indices])
    with multiprocessing.get_context("fork").Pool(1) as pool:
        child = pool.apply_async(take_rows, (values, indices)).get(timeout=60)
    assert np.array_equal(child, values[indices])


def test_a_builder_being_built_is_seen_by_the_commands_exit(monkeypatch):
    """While a device's builder kernels build (a DevicesOpening's thread builds them after the
    devices are open), the console leaves past the interpreter's teardown, which would wait for
    that thread (app/cli/console.py), as around a scene's program's build."""
    import threading

    from pathtrace.cli import console
    from pathtrace.compiler import builder
    held, started = threading.Event(), threading.Event()

    class Slow:
        def __init__(self, queue):
            started.set()
            held.wait(30)
    monkeypatch.setattr(builder, "Builder", Slow)
    monkeypatch.setattr(builder, "_builders", {})
    thread = threading.Thread(target=builder.builder_for, args=("a queue",))
    thread.start()
    assert started.wait(30) and builder.building() and console._building()
    held.set()
    thread.join()
    assert not builder.building()
