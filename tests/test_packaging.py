"""The installed package (./install.sh does a normal, non-editable `pip install .`) renders on its
own: kernels, shaders and assets come from inside the wheel, not from this checkout."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = Path(sys.executable).parent / "pathtrace"


@pytest.fixture
def installed():
    if not SCRIPT.exists():
        pytest.skip("pathtrace is not installed in this Python environment (./install.sh does it)")
    return SCRIPT


def clean_env():
    return {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}


def test_installed_package_is_not_the_checkout(installed, tmp_path):
    r = subprocess.run([sys.executable, "-c", "import app.resources as r; print(r.resource_dir('kernels'))"],
                       cwd=tmp_path, env=clean_env(), capture_output=True, text=True)
    kernels = Path(r.stdout.strip())
    assert r.returncode == 0 and kernels.is_dir(), r.stdout + r.stderr
    assert "site-packages" in kernels.parts and kernels != ROOT / "kernels"
    for folder in ("kernels", "shaders", "assets/envmaps", "assets/scenes"):
        assert (kernels.parent / folder).is_dir()


def test_installed_command_renders_the_hdr_demo(installed, tmp_path):
    out = tmp_path / "demo.png"
    r = subprocess.run([installed, "render", "demo", "-o", out, "--size", "32x18", "--spp", "2", "-q"],
                       cwd=tmp_path, env=clean_env(), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:4] == b"\x89PNG"
