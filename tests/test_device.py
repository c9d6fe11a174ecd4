"""The kernel cache (app/device/opencl.py build_cached): an entry that is not a regular file is not
opened (a FIFO blocked for ever), a write that fails (a full disk) leaves nothing behind, and on
PoCL, which keeps its own, it is not used."""

import os
import subprocess
import sys

import pytest

from pathtrace.device.opencl import build_cached

SOURCE = "kernel void one(global int *a) { a[0] = 1; }"
BUILD = f"""
import pyopencl as cl
import pathtrace.device.opencl as d
from pathtrace.device.opencl import build_cached, choose_device
b = choose_device({os.environ.get("PATHTRACE_TEST_DEVICE", "cpu")!r})
d.keeps_own_cache = lambda device: False      # PoCL keeps its own cache, which leaves ours unused
r = build_cached(b.context, b.device.device, {SOURCE!r}, [])
print("cached" if r.cached else "built")
"""


def build(cache, extra=""):
    """BUILD in a process of its own, for what only a process shows: a build that hangs (killed
    at the time limit), two processes at once."""
    return subprocess.run([sys.executable, "-c", extra + BUILD], env={**os.environ, "PATHTRACE_CACHE": str(cache)},
                          capture_output=True, text=True, timeout=120)


def build_here(backend, cache, monkeypatch, options=()) -> str:
    """BUILD in this process, on the tests' device ("built" or "cached"): the entry is read from
    and written to the disk as in a process of its own, without a process's start, imports and
    device (about 1.6 s of CPU a build, issue #60)."""
    import pathtrace.device.opencl as d
    monkeypatch.setenv("PATHTRACE_CACHE", str(cache))
    monkeypatch.setattr(d, "keeps_own_cache", lambda device: False)   # as BUILD
    return "cached" if d.build_cached(backend.context, backend.device.device, SOURCE, list(options)).cached else "built"


def test_a_cache_entry_that_is_a_fifo_is_not_opened(backend, tmp_path):
    from pathtrace.device.opencl import cache_entry
    assert build(tmp_path).stdout.strip() == "built"
    assert build(tmp_path).stdout.strip() == "cached"
    entry = tmp_path / cache_entry(backend.device.device, SOURCE, [], True).name
    entry.unlink()
    os.mkfifo(entry)
    r = build(tmp_path)                  # hung in open() before
    assert r.returncode == 0 and r.stdout.strip() == "built", r.stderr


def test_a_full_disk_leaves_no_partial_cache_file(backend, tmp_path, monkeypatch):
    """The write fails half-way (ENOSPC): the build still succeeds, and no .tmp file is left."""
    import builtins
    import errno
    import io

    import pathtrace.io.cache_files as files

    class Full(io.FileIO):
        def write(self, data):
            super().write(bytes(data)[: len(data) // 2])
            raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(files, "open", lambda path, mode="r": Full(path, mode) if "w" in mode else builtins.open(path, mode),
                        raising=False)
    assert build_here(backend, tmp_path, monkeypatch) == "built"
    assert not list(tmp_path.glob("*.tmp*")) and not list(tmp_path.glob("*.bin"))


def test_a_cache_entry_keeps_the_options_its_binary_was_built_with(backend, tmp_path, monkeypatch):
    """A register cap chosen at build time (app/device/occupancy.py) must apply again when the cached
    binary is built for the device: the entry carries the options."""
    from pathtrace.device.opencl import _read_cached
    assert build_here(backend, tmp_path, monkeypatch, ["-DONE=1"]) == "built"
    assert ["-DONE=1"] in [_read_cached(p)[0] for p in tmp_path.glob("*.bin")]


def test_pocl_keeps_the_kernels_in_its_own_cache_alone(backend, tmp_path, monkeypatch):
    """Asking PoCL for a program's binary, to store it, compiled every kernel of the program first
    (4 s for the render program on two cores): where the driver is PoCL, pathtrace's cache
    stays empty and every build is PoCL's, which its own cache makes fast the second time."""
    from pathtrace.device.opencl import keeps_own_cache
    device = backend.device.device
    assert keeps_own_cache(device) == ("Portable Computing Language" in device.platform.name)
    monkeypatch.setenv("PATHTRACE_CACHE", str(tmp_path))
    for _ in range(2):
        r = build_cached(backend.context, device, SOURCE, [])
        assert not r.cached or not keeps_own_cache(device)
    assert bool(list(tmp_path.glob("*.bin"))) != keeps_own_cache(device)


def only_entry(backend, cache, monkeypatch):
    """The one-line kernel's cache entry, found by its key."""
    from pathtrace.device.opencl import cache_entry
    monkeypatch.setenv("PATHTRACE_CACHE", str(cache))
    entry = cache_entry(backend.device.device, SOURCE, [], True)
    assert entry.is_file()
    return entry


def test_a_damaged_cache_entry_is_built_again_and_replaced(backend, tmp_path, monkeypatch):
    assert build_here(backend, tmp_path, monkeypatch) == "built"
    entry = only_entry(backend, tmp_path, monkeypatch)
    data = bytearray(entry.read_bytes())
    data[len(data) // 2] ^= 0xFF                 # a flipped bit: its checksum no longer matches
    entry.write_bytes(bytes(data))
    assert build_here(backend, tmp_path, monkeypatch) == "built"
    assert build_here(backend, tmp_path, monkeypatch) == "cached"


def test_a_foreign_binary_in_a_cache_entry_is_built_again(backend, tmp_path, monkeypatch):
    """A whole entry whose binary the driver refuses (another driver's, or garbage): rebuilt."""
    from pathtrace.io.cache_files import write_entry
    assert build_here(backend, tmp_path, monkeypatch) == "built"
    entry = only_entry(backend, tmp_path, monkeypatch)
    write_entry(entry, b"\n", b"\x7fELF not a binary this driver reads" * 8)
    assert build_here(backend, tmp_path, monkeypatch) == "built"
    assert build_here(backend, tmp_path, monkeypatch) == "cached"


def test_two_processes_building_the_same_program_leave_one_whole_entry(tmp_path):
    """Each writes a temporary file of its own and renames it over the entry: whichever rename
    comes last, the entry is whole, and no temporary file stays."""
    from pathtrace.device.opencl import _read_cached
    env = {**os.environ, "PATHTRACE_CACHE": str(tmp_path)}
    runs = [subprocess.Popen([sys.executable, "-c", BUILD], env=env, stdout=subprocess.PIPE, text=True)
            for _ in range(2)]
    outputs = [r.communicate(timeout=300)[0].strip() for r in runs]
    assert all(r.returncode == 0 for r in runs) and set(outputs) <= {"built", "cached"}
    assert all(_read_cached(p) is not None for p in tmp_path.glob("*.bin"))
    assert not list(tmp_path.glob("*.tmp*"))
    assert build(tmp_path).stdout.strip() == "cached"


def test_without_an_opencl_platform_one_line_says_how_to_get_one(tmp_path):
    """With the system's OpenCL drivers hidden (an empty vendors folder for the ICD loader), each
    command that needs a device says in one line how to get one, root or not."""
    env = {**os.environ, "OCL_ICD_VENDORS": str(tmp_path)}
    for args in (["devices"], ["render", "simple", "-o", str(tmp_path / "o.png")]):
        r = subprocess.run([sys.executable, "-m", "pathtrace", *args], env=env, capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 1 and not (tmp_path / "o.png").exists()
        last = r.stderr.strip().splitlines()[-1]
        assert last == ("pathtrace: error: no OpenCL device found: for the CPU without root, pip install "
                        "pocl-binary-distribution (pathtrace's extra [cpu]); on Debian/Ubuntu, apt install "
                        "pocl-opencl-icd; for a GPU, its vendor's OpenCL driver"), r.stderr


def test_a_device_opens_with_the_generic_program_only_where_it_renders_from_a_cache(backend, tmp_path, monkeypatch):
    """open_device builds the generic program where the mode renders with it and building it
    reads a cache (built_before). A first start, whose cache holds neither, builds the display's
    small program and its first image waits for the scene's own program, which PoCL builds and
    launches sooner (cornell-box cold on two cores: 4.1 s to the first image before, 2.9 s); the
    specialised mode never builds it; once the generic program is built (`pathtrace devices
    --check`), the next start builds it at once from the cache."""
    from pathtrace.device.opencl import open_device
    monkeypatch.setenv("PATHTRACE_CACHE", str(tmp_path))
    assert open_device(backend.device, mode="auto").built_generic(False) is None
    open_device(backend.device, mode="generic").generic(False)
    assert open_device(backend.device, mode="auto").built_generic(False) is not None
    assert open_device(backend.device, mode="specialised").built_generic(False) is None


def test_a_start_with_no_writable_cache_still_renders(tmp_path):
    """#55: with XDG_CACHE_HOME under a file, where no cache folder can be made (as in a read-only
    home), a render still writes its image, with no traceback: PyOpenCL's cache is off and PoCL
    compiles in a temporary folder, removed at the exit (app/device/driver_caches.py)."""
    blocked = tmp_path / "file"
    blocked.write_text("")
    (tmp_path / "tmp").mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("POCL_CACHE_DIR", "PYOPENCL_NO_CACHE", "PATHTRACE_CACHE",
                                                             "PATHTRACE_BVH_CACHE", "PATHTRACE_SCENE_CACHE")}
    env.update(XDG_CACHE_HOME=str(blocked / "cache"), TMPDIR=str(tmp_path / "tmp"))
    out = tmp_path / "out.png"
    r = subprocess.run([sys.executable, "-m", "pathtrace", "render", "cornell-box", "--size", "16x16", "--spp", "1",
                        "--device", "cpu", "-o", out], env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert out.stat().st_size > 0 and not any((tmp_path / "tmp").iterdir())


@pytest.mark.parametrize("command", [["devices"], ["render", "simple", "--device", "all", "--size", "8x8", "--spp", "1",
                                                    "-o", "o.png"]])
def test_an_unwritable_pocl_cache_is_named_where_no_device_is_found(tmp_path, command):
    """PoCL lists no device where it cannot write POCL_CACHE_DIR: the one line says that, not
    how to install an OpenCL driver the machine has, nor that no device builds the kernels."""
    blocked = tmp_path / "file"
    blocked.write_text("")
    r = subprocess.run([sys.executable, "-m", "pathtrace", *command], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                       env={**os.environ, "POCL_CACHE_DIR": str(blocked / "pocl"), "OCL_ICD_VENDORS": "/etc/OpenCL/vendors"})
    if r.returncode == 0:       # a platform that lists devices without that cache (a GPU's): nothing to say
        return
    assert r.returncode == 1 and r.stderr.splitlines()[-1].startswith(
        f"pathtrace: error: no OpenCL device found (PoCL lists none where POCL_CACHE_DIR, {blocked / 'pocl'}, cannot "
        "be written): "), r.stderr
