"""Scenes and images that would not fit: refused with one line before anything is allocated, on
the host (the BVH build) and on the device (its largest allocation and its global memory)."""

from types import SimpleNamespace

import numpy as np
import pytest

import pathtrace.cli.main as cli
import pathtrace.cli.progress

from pathtrace.compiler import compiled
from pathtrace.compiler.compiled import BUILD_HOST_BYTES, check_memory
from pathtrace.device.opencl import check_fits
from pathtrace.errors import UserError
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene

SMALL_DEVICE = SimpleNamespace(name="Tiny GPU ", max_mem_alloc_size=1 << 20, global_mem_size=3 << 20)


def test_a_buffer_larger_than_the_largest_allocation_is_refused():
    with pytest.raises(UserError, match=r"^big: its buffer 'BVH' needs 2 MB; Tiny GPU allocates at most 1 MB at once$"):
        check_fits(SMALL_DEVICE, {"BVH": 2 << 20, "spheres": 10}, "big")


def test_buffers_larger_together_than_global_memory_are_refused():
    with pytest.raises(UserError, match=r"^big needs 4 MB of device memory; Tiny GPU has 3 MB$"):
        check_fits(SMALL_DEVICE, {"a": 1 << 20, "b": 1 << 20, "c": 1 << 20, "d": 1 << 20}, "big")
    check_fits(SMALL_DEVICE, {"a": 1 << 20, "b": 1 << 20, "c": 1 << 20}, "fits")


def test_a_scene_too_large_for_the_device_is_refused_before_its_build():
    # 20000 spheres need at most 13333 4-wide BVH nodes of 128 bytes: 1.6 MB in one buffer
    with pytest.raises(UserError, match="spheres20k: its buffer 'BVH' needs 1.63 MB;"):
        check_memory("spheres20k", 20000, 0, SMALL_DEVICE)
    check_memory("spheres8k", 8000, 0, SMALL_DEVICE)


def test_a_build_larger_than_the_host_memory_is_refused(monkeypatch):
    monkeypatch.setattr(compiled, "available_host_memory", lambda: 10 * BUILD_HOST_BYTES * 1000)
    with pytest.raises(UserError, match="building the BVH of 64000 primitives needs about 19.5 MB of memory; 3.05 MB is available"):
        compiled.compile_scene(load_scene("spheres64k"))


def test_a_generated_scene_too_large_to_make_is_refused_before_it_is_made(monkeypatch):
    """spheres100M took 24 GB and the kernel's killer ended it, without a word: a generated
    scene is checked before its arrays are made (making one takes more than its BVH build's
    check, which runs once it is made), and its count is bounded with the k or M applied."""
    import pathtrace.compiler.memory
    from pathtrace.scene.builtin import MAKE_SPHERE_BYTES, builtin_maker
    monkeypatch.setattr(pathtrace.compiler.memory, "available_host_memory", lambda: 10_000 * BUILD_HOST_BYTES)
    with pytest.raises(UserError, match=r"^spheres20k: making 20,000 spheres and building their BVH needs about "):
        load_scene("spheres20k")
    with pytest.raises(UserError, match=r"^heightfield1M: making 1,000,000 triangles"):
        load_scene("heightfield1M")
    monkeypatch.setattr(pathtrace.compiler.memory, "available_host_memory",
                        lambda: 20_000 * (MAKE_SPHERE_BYTES[1] + BUILD_HOST_BYTES))
    assert len(load_scene("spheres20k").spheres) == 20_000
    assert builtin_maker("spheres100M") is not None and builtin_maker("spheres200M") is None
    assert builtin_maker("spheres100000k") is not None and builtin_maker("spheres100001k") is None
    with pytest.raises(UserError, match="generated: spheresN.-diffuse. and heightfieldN, N from 1 to 100M"):
        load_scene("spheres0")


def test_an_image_too_large_for_the_device_is_refused(backend):
    r = Renderer(backend, load_scene("simple"), 8, 8)
    side = int((backend.device.device.max_mem_alloc_size // 16) ** 0.5) + 1
    with pytest.raises(UserError, match=f"the {side}x{side} image of simple: its buffer 'sum' needs"):
        r.resize(side, side)
    assert (r.width, r.height) == (8, 8)      # the renderer still works at its old size
    r.add_samples(1)
    assert np.all(np.isfinite(r.mean()))


def test_the_command_line_says_what_does_not_fit(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(compiled, "available_host_memory", lambda: 1 << 20)
    code = cli.main(["render", "spheres8k", "-o", str(tmp_path / "a.png"), "--size", "8x8", "--spp", "1", "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and err[-1].startswith("pathtrace: error: spheres8k: building the BVH of 8000 primitives needs about")
    assert not list(tmp_path.iterdir())


def test_a_slow_build_shows_its_progress(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(pathtrace.cli.progress, "PROGRESS_AFTER", 0.0)
    code = cli.main(["render", "spheres8k", "-o", str(tmp_path / "a.png"), "--size", "8x8", "--spp", "1"])
    assert code == 0
    assert "spheres8k: building the BVH: 100%" in capsys.readouterr().err


def test_an_image_too_large_to_read_back_is_refused(backend, monkeypatch):
    import pathtrace.rendering.renderer
    r = Renderer(backend, load_scene("simple"), 8, 8)
    monkeypatch.setattr(pathtrace.rendering.renderer, "available_host_memory", lambda: 1 << 20)
    with pytest.raises(UserError, match="the 4096x4096 image of simple needs about .* of memory to render, read back"):
        r.resize(4096, 4096)
    assert (r.width, r.height) == (8, 8)


def fake_cgroup(tmp_path, membership, files):
    """A /proc/self/cgroup and a hierarchy holding `files` (path: text)."""
    (tmp_path / "cgroup").write_text(membership)
    for path, text in files.items():
        (tmp_path / "fs" / path).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "fs" / path).write_text(text)
    return str(tmp_path / "fs"), str(tmp_path / "cgroup")


@pytest.mark.parametrize("layout", ["v2", "v2 at the root", "v1", "v1 at the root"])
def test_a_control_group_limit_caps_the_memory_available(tmp_path, layout):
    """A container's or a batch job's memory limit less its usage, cgroup v2 or v1, whether the
    group's files sit at its path or (inside a container) at the hierarchy's root."""
    from pathtrace.compiler.memory import cgroup_memory_left
    at_root = layout.endswith("root")
    if layout.startswith("v2"):
        folder = "" if at_root else "job/"
        root, membership = fake_cgroup(tmp_path, "0::/job\n", {f"{folder}memory.max": "3000000\n",
                                                               f"{folder}memory.current": "1000000\n"})
    else:
        folder = "memory/" if at_root else "memory/job/"
        root, membership = fake_cgroup(tmp_path, "5:cpu:/\n4:memory:/job\n", {
            f"{folder}memory.limit_in_bytes": "3000000\n", f"{folder}memory.usage_in_bytes": "1000000\n"})
    assert cgroup_memory_left(root, membership) == 2000000


@pytest.mark.parametrize("limit", ["max\n", "9223372036854771712\n"])
def test_no_control_group_limit_leaves_meminfo_in_charge(tmp_path, limit):
    from pathtrace.compiler.memory import cgroup_memory_left
    name = "memory.max" if limit == "max\n" else "memory/memory.limit_in_bytes"
    usage = "memory.current" if limit == "max\n" else "memory/memory.usage_in_bytes"
    line = "0::/\n" if limit == "max\n" else "4:memory:/\n"
    root, membership = fake_cgroup(tmp_path, line, {name: limit, usage: "5\n"})
    assert cgroup_memory_left(root, membership) is None
    assert cgroup_memory_left(str(tmp_path / "none"), str(tmp_path / "none")) is None


def test_an_address_space_limit_is_respected(tmp_path):
    """Under ulimit -v, an image that cannot fit gets one line (PoCL aborted on an assertion when
    its allocation failed), and one that fits renders."""
    import resource
    import subprocess
    import sys
    from pathlib import Path

    def limited():
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, resource.RLIM_INFINITY))
    root = Path(__file__).resolve().parent.parent
    run = lambda size: subprocess.run(  # noqa: E731
        [sys.executable, "-c", "import pathtrace.compiler.memory as m; print(m.address_space_left())"] if size is None else
        [sys.executable, "-m", "pathtrace", "render", "simple", "-o", str(tmp_path / "o.png"), "--size", size, "--spp", "1"],
        cwd=root, preexec_fn=limited, capture_output=True, text=True, timeout=300)
    left = int(run(None).stdout)
    assert 0 < left < 3 << 30
    r = run("8000x8000")
    assert r.returncode == 1 and r.stderr.strip().splitlines()[-1].startswith(
        "pathtrace: error: the 8000x8000 image of simple needs about"), r.stderr
    assert not list(tmp_path.iterdir())
    assert run("64x64").returncode == 0 and (tmp_path / "o.png").exists()


def test_render_names_the_device_a_scene_does_not_fit(monkeypatch, capsys, tmp_path):
    """The device's line, then the one error line: the scene compiles while the device opens, so
    the refusal comes after the device is known."""
    import pathtrace.device.opencl as opencl
    monkeypatch.setattr(opencl, "check_fits", lambda device, buffers, name: (_ for _ in ()).throw(
        UserError(f"{name} needs more than {device.name.strip()} has")))
    code = cli.main(["render", "simple", "-o", str(tmp_path / "a.png"), "--size", "8x8", "--spp", "1", "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and err[0].startswith("device: ") and err[-1].startswith("pathtrace: error: simple needs more than")
    assert not (tmp_path / "a.png").exists()
