"""The package as users install it (`./install.sh`, a normal `pip install .`): the source folder
app/ becomes the package `pathtrace`, which renders on its own, its kernels, shaders and assets
coming from inside the wheel, not from this checkout. The wheel is built here and installed into
a folder of its own, beside the editable install the tests run on."""

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """The built wheel, and a folder it is installed into (without its dependencies, which the
    test environment has)."""
    tmp = tmp_path_factory.mktemp("wheel")
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    r = subprocess.run([*pip, "wheel", "--no-deps", "--no-build-isolation", "-w", tmp / "dist", ROOT],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    built = next((tmp / "dist").glob("pathtrace-*.whl"))
    r = subprocess.run([*pip, "install", "--no-deps", "--target", tmp / "site", built],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return built, tmp / "site"


def run_installed(site: Path, args: list, cwd: Path):
    """Python with the installed wheel first on its path (before the editable install's hook)."""
    env = {**os.environ, "PYTHONPATH": str(site)}
    return subprocess.run([sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=300)


def test_wheel_holds_every_source_file_under_the_name_pathtrace(wheel):
    names = set(zipfile.ZipFile(wheel[0]).namelist())
    for folder, target in (("app", "pathtrace"), ("kernels", "pathtrace/kernels"),
                           ("shaders", "pathtrace/shaders"), ("assets", "pathtrace/assets")):
        for f in (ROOT / folder).rglob("*"):
            if f.is_file() and "__pycache__" not in f.parts and f.suffix != ".pyc":
                assert f"{target}/{f.relative_to(ROOT / folder).as_posix()}" in names, f
    assert not any(n.startswith("app/") for n in names)


def test_installed_package_is_not_the_checkout(wheel, tmp_path):
    r = run_installed(wheel[1], ["-c", "import pathtrace, pathtrace.resources as r; "
                                       "print(pathtrace.__file__); print(r.resource_dir('kernels'))"], tmp_path)
    assert r.returncode == 0, r.stderr
    package, kernels = (Path(line) for line in r.stdout.split())
    assert package.parent == wheel[1] / "pathtrace" and kernels == wheel[1] / "pathtrace" / "kernels"
    for folder in ("kernels", "shaders", "assets/envmaps", "assets/scenes"):
        assert (kernels.parent / folder).is_dir()


def test_installed_package_renders_the_hdr_demo(wheel, tmp_path):
    out = tmp_path / "demo.png"
    r = run_installed(wheel[1], ["-m", "pathtrace", "render", "demo", "-o", out, "--size", "32x18",
                                 "--spp", "2", "-q"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:4] == b"\x89PNG"


def test_installed_api_renders_to_numpy(wheel, tmp_path):
    r = run_installed(wheel[1], ["-c", "import pathtrace; print(pathtrace.render(pathtrace.load('simple'), "
                                       "spp=4, size=(64, 36)).shape)"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "(36, 64, 3)"
