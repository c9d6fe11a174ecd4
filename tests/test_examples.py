"""The scripts of examples/ run as a user runs them (small, to keep the suite quick) and write
their images."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DEVICE = os.environ.get("PATHTRACE_TEST_DEVICE", "cpu")


@pytest.mark.parametrize("script, args", [
    ("material_sweep.py", ["--size", "40x30", "--spp", "4"]),
    ("convergence.py", ["--size", "32x18", "--spp", "16"]),
])
def test_example_writes_its_image(tmp_path, script, args):
    out = tmp_path / "out.png"
    r = subprocess.run([sys.executable, ROOT / "examples" / script, "-o", out, "--device", DEVICE, *args],
                       cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:4] == b"\x89PNG" and f"wrote {out}" in r.stdout


def test_the_convergence_plot_without_matplotlib_says_how_to_get_it(tmp_path):
    """matplotlib is not among pathtrace's requirements: without it, one line saying how to
    install it, not a traceback (a new user's run found one)."""
    (tmp_path / "matplotlib.py").write_text("raise ImportError('no matplotlib here')\n")   # shadows it
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")]))}
    r = subprocess.run([sys.executable, ROOT / "examples" / "convergence.py", "-o", tmp_path / "out.png"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and "Traceback" not in r.stderr, r.stderr
    assert r.stderr.strip().splitlines() == [
        "convergence.py: the plot needs matplotlib, which pathtrace does not install: "
        ".venv/bin/python -m pip install matplotlib"]


def test_the_examples_say_a_bad_size_in_one_line_and_their_help_needs_no_plotting_library(tmp_path):
    """`--size big` ended in a ValueError's traceback, and convergence.py --help asked for
    matplotlib (a new user's run, 2026-12-03)."""
    for name in ("material_sweep.py", "convergence.py"):
        r = subprocess.run([sys.executable, ROOT / "examples" / name, "--size", "big"], capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 2 and r.stderr.strip().splitlines()[-1] == \
            f"{name}: error: argument --size: 'big' is not WIDTHxHEIGHT, e.g. 1920x1080", r.stderr
    (tmp_path / "matplotlib.py").write_text("raise ImportError('no matplotlib here')\n")   # shadows it
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")]))}
    r = subprocess.run([sys.executable, ROOT / "examples" / "convergence.py", "--help"], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and "usage:" in r.stdout, r.stderr
