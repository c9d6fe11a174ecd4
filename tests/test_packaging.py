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


# a kernel of one line built and run on the first OpenCL device: whether a PoCL works here at all
ONE_LINE_KERNEL = """import numpy as np, pyopencl as cl
ctx = cl.Context([cl.get_platforms()[0].get_devices()[0]])
k = cl.Program(ctx, "kernel void one(global int *a) { a[0] = 1; }").build().one
a = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, 4)
q = cl.CommandQueue(ctx)
k(q, (1,), None, a)
out = np.zeros(1, np.int32)
cl.enqueue_copy(q, out, a)
assert out[0] == 1
"""


def test_the_cpu_extra_renders_with_the_system_opencl_hidden(tmp_path):
    """`pip install 'pathtrace[cpu]'` without root: the extra's PoCL from PyPI
    (pocl-binary-distribution, downloaded here as pip does) ships its ICD inside PyOpenCL's
    package, where PyOpenCL's loader looks (PYOPENCL_HOME/.libs). With the system's ICDs hidden
    (OCL_ICD_VENDORS an empty folder), a PyOpenCL with it lists that PoCL alone and renders the
    image the system's PoCL renders. Where that PoCL cannot build even a one-line kernel on this
    CPU (PoCL 3.0 from PyPI names no CPU for a virtual machine's "AMD EPYC": "unknown target CPU
    'generic'"), pathtrace says so in one line and exits non-zero, and the system's PoCL still
    renders. (PyOpenCL is copied beside the extra's files, as one site-packages would hold them,
    rather than a whole environment installed.)"""
    import shutil
    import tomllib

    import numpy as np
    import pyopencl

    from pathtrace.io.images import read_hdr
    extra = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]["cpu"]
    site = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "--disable-pip-version-check", "-q", "install", "--no-deps",
                        "--target", site, *extra], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    shutil.copytree(Path(pyopencl.__file__).parent, site / "pyopencl", dirs_exist_ok=True)
    (tmp_path / "no-vendors").mkdir()
    env = {**os.environ, "PYTHONPATH": f"{site}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
           "OCL_ICD_VENDORS": str(tmp_path / "no-vendors"), "POCL_CACHE_DIR": str(tmp_path / "pocl"),
           "XDG_CACHE_HOME": str(tmp_path / "cache")}
    hidden = subprocess.run([sys.executable, "-m", "pathtrace", "devices"], env={**env, "PYTHONPATH": ""},
                            capture_output=True, text=True, timeout=60)
    assert hidden.returncode == 1 and "no OpenCL device found" in hidden.stderr    # nothing else to find
    listed = subprocess.run([sys.executable, "-m", "pathtrace", "devices"], env=env, capture_output=True, text=True,
                            timeout=60)
    assert listed.returncode == 0 and len(listed.stdout.splitlines()) == 1, listed.stdout + listed.stderr
    assert "Portable Computing Language" in listed.stdout and str(site) in subprocess.run(
        [sys.executable, "-c", "import pyopencl; print(pyopencl.__file__)"], env=env, capture_output=True,
        text=True, timeout=60).stdout
    args = ["render", "cornell-box", "--size", "32x32", "--spp", "16", "--program", "generic", "-q"]
    r = subprocess.run([sys.executable, "-m", "pathtrace", *args, "-o", tmp_path / "pypi.exr"], env=env,
                       capture_output=True, text=True, timeout=600)
    builds = subprocess.run([sys.executable, "-c", ONE_LINE_KERNEL], env=env, capture_output=True, text=True, timeout=120)
    if builds.returncode != 0:         # the extra's PoCL fails on this CPU, pathtrace or not
        assert r.returncode == 1 and "Traceback" not in r.stderr, r.stderr
        assert r.stderr.splitlines()[-1] == "pathtrace: error: device: no device matching 'auto' can build the kernels"
        assert "cannot build the kernels: " in r.stderr and not (tmp_path / "pypi.exr").exists(), r.stderr
    else:
        assert r.returncode == 0, r.stderr
    r = subprocess.run([sys.executable, "-m", "pathtrace", *args, "-o", tmp_path / "system.exr", "--device", "cpu"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    if builds.returncode != 0:
        return
    pypi, system = (read_hdr(tmp_path / f"{n}.exr", n, "image") for n in ("pypi", "system"))
    np.testing.assert_allclose(pypi, system, rtol=1e-4, atol=1e-5)
