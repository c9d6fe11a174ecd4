"""Image files: outputs written all or nothing under any valid name, with the permissions and
links a user expects; maps and scene files that are not regular files, or claim absurd sizes,
refused in one line (#12)."""

import os
import stat

import numpy as np
import pytest

from pathtrace.io import images as image_io
from pathtrace.errors import UserError
from pathtrace.io.images import Output, read_hdr, write_image, write_images
from tests.test_cli import GOOD, pathtrace, write

IMAGE = np.random.default_rng(0).random((6, 8, 3)).astype(np.float32)


@pytest.mark.parametrize("suffix", [".png", ".exr", ".pfm"])
def test_a_name_that_is_not_utf8_is_written(tmp_path, suffix):
    name = os.fsdecode(b"caf\xe9" + suffix.encode())
    r = pathtrace("render", "simple", "-o", tmp_path / name, "--size", "8x6", "--spp", "1", "-q")
    assert r.returncode == 0, r.stderr
    assert os.listdir(tmp_path) == [name] and (tmp_path / name).stat().st_size > 0


@pytest.mark.parametrize("suffix", [".exr", ".hdr", ".pfm"])
def test_maps_in_a_folder_whose_name_is_not_utf8_are_written_and_read(tmp_path, suffix):
    """OpenEXR's bindings take only UTF-8 names: pathtrace hands them bytes instead."""
    folder = tmp_path / os.fsdecode(b"caf\xe9")
    folder.mkdir()
    path = folder / f"map{suffix}"
    write_image(path, IMAGE)
    back = read_hdr(path, "environment.map")
    # Radiance's RGBE keeps 8 bits of mantissa under the pixel's largest channel's exponent
    step = IMAGE.max(-1, keepdims=True) / 128 if suffix == ".hdr" else 1e-6
    assert np.all(np.abs(back - IMAGE) <= step)


def test_a_long_name_is_written(tmp_path):
    path = tmp_path / ("x" * 246 + ".png")          # 250 characters: valid; the temporary name is short
    write_image(path, IMAGE)
    assert path.stat().st_size > 0 and len(os.listdir(tmp_path)) == 1


def test_new_files_follow_the_umask_and_replaced_ones_keep_their_mode(tmp_path):
    old = os.umask(0o027)
    try:
        write_image(tmp_path / "new.png", IMAGE)
        kept = tmp_path / "kept.png"
        kept.write_bytes(b"old")
        kept.chmod(0o604)
        write_image(kept, IMAGE)
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "new.png").stat().st_mode) == 0o640
    assert stat.S_IMODE(kept.stat().st_mode) == 0o604 and kept.read_bytes()[:4] == b"\x89PNG"


def test_a_symbolic_link_stays_a_link(tmp_path):
    target = tmp_path / "real.png"
    target.write_bytes(b"old")
    link = tmp_path / "link.png"
    link.symlink_to(target)
    write_image(link, IMAGE)
    assert link.is_symlink() and target.read_bytes()[:4] == b"\x89PNG"


def test_several_outputs_are_written_all_or_none(tmp_path, monkeypatch):
    first = tmp_path / "a.png"
    first.write_bytes(b"old")

    def fail(path, rgb, layers):
        raise RuntimeError("disk full")
    monkeypatch.setattr(image_io, "_write_exr", fail)
    with pytest.raises(UserError, match="cannot write .*b.exr': disk full"):
        write_images([Output(first, IMAGE), Output(tmp_path / "b.exr", IMAGE)])
    assert first.read_bytes() == b"old" and sorted(os.listdir(tmp_path)) == ["a.png"]


def special_files(tmp_path):
    fifo = tmp_path / "fifo.hdr"
    os.mkfifo(fifo)
    (tmp_path / "folder.hdr").mkdir()
    return {"fifo": fifo, "folder": tmp_path / "folder.hdr", "device": "/dev/zero"}


@pytest.mark.parametrize("kind", ["fifo", "folder", "device"])
def test_a_map_that_is_not_a_regular_file_is_refused(tmp_path, kind):
    path = special_files(tmp_path)[kind]
    with pytest.raises(UserError, match=f"environment map '{path}' is not a regular file"):
        read_hdr(path, "scene.toml: environment.map")


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_scene_file_that_is_not_a_regular_file_is_refused_at_once(tmp_path, kind):
    path = special_files(tmp_path)[kind]
    r = pathtrace("render", path, "-o", tmp_path / "o.png", "--spp", "1")
    assert r.returncode == 1 and "is not a regular file" in r.stderr and len(r.stderr.splitlines()) == 1


@pytest.mark.parametrize("name,header", [("huge.pfm", b"PF\n99999 99999\n-1.0\n"),
                                         ("huge.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 30000 +X 30000\n")])
def test_a_map_claiming_a_huge_size_is_refused_before_decoding(tmp_path, name, header):
    (tmp_path / name).write_bytes(header + b"\0" * 64)
    with pytest.raises(UserError, match=r"claims \d+x\d+ pixels, more than pathtrace takes"):
        read_hdr(tmp_path / name, "environment.map")


def test_a_truncated_map_gets_our_line_only(tmp_path):
    data = open("assets/envmaps/venice_sunset_1k.hdr", "rb").read()
    (tmp_path / "cut.hdr").write_bytes(data[: len(data) // 2])
    scene = write(tmp_path, GOOD.replace("color = 0.5", 'map = "cut.hdr"'))
    r = pathtrace("render", scene, "-o", tmp_path / "o.png", "--spp", "1")
    assert r.returncode == 1 and r.stderr.count("\n") == 1, r.stderr
    assert "is not a readable HDR image" in r.stderr


def test_a_cut_exr_map_prints_nothing_of_openexrs_own(tmp_path):
    """An EXR cut in half: OpenEXR's C library writes lines to the standard error's descriptor and
    its C++ layer one to the standard output's ("Warning: Exception raised reading pixel data"),
    which only a process shows: none of them comes out, only pathtrace's line."""
    from pathtrace.io.images import _write_exr
    _write_exr(str(tmp_path / "full.exr"), np.random.default_rng(0).random((256, 512, 3)).astype(np.float32))
    data = (tmp_path / "full.exr").read_bytes()
    (tmp_path / "cut.exr").write_bytes(data[:len(data) // 2])
    scene = write(tmp_path, GOOD.replace("color = 0.5", 'map = "cut.exr"'))
    r = pathtrace("render", scene, "-o", tmp_path / "o.png", "--spp", "1", "--size", "8x4", "-q")
    assert r.returncode == 1 and r.stdout == "", r.stdout
    assert r.stderr.splitlines() == [f"pathtrace: error: {scene}: environment.map: '{tmp_path / 'cut.exr'}' is not a "
                                     "readable HDR image (.hdr, .exr or .pfm)"], r.stderr


@pytest.mark.parametrize("closed", [1, 2])
def test_a_read_with_a_standard_descriptor_closed_keeps_the_other(tmp_path, closed):
    """The quieting around OpenEXR's reads in a process whose standard output or error is
    closed: the read succeeds, and the other descriptor still writes where it did (a copy of
    standard output that took the closed descriptor 2 was quieted and restored as 1: the
    process's output lost for good)."""
    import subprocess
    import sys
    from pathtrace.io.images import _write_exr
    _write_exr(str(tmp_path / "map.exr"), np.ones((8, 16, 3), np.float32))
    other = 3 - closed
    code = ("import os; from pathlib import Path; from pathtrace.io.images import read_hdr; "
            f"shape = read_hdr(Path({str(tmp_path / 'map.exr')!r}), 'x').shape; "
            f"os.write({other}, str(shape).encode() + b' after')")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       preexec_fn=lambda: os.close(closed))
    assert r.returncode == 0 and (r.stdout, r.stderr)[other - 1] == "(8, 16, 3) after", (r.stdout, r.stderr)


def test_an_exposure_beyond_100_stops_is_refused_before_rendering(tmp_path):
    r = pathtrace("render", "simple", "-o", tmp_path / "o.png", "--exposure", "1100")
    assert r.returncode == 2 and "1100.0 stops is out of range (must be -100 to 100)" in r.stderr
