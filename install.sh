#!/usr/bin/env bash
# Sets pathtrace up on Debian or Ubuntu: the system's OpenCL and OpenGL pieces, a virtual
# environment in .venv, and pathtrace installed into it.
#   ./install.sh          what rendering and the viewer need (a normal install: a copy)
#   ./install.sh --dev    also Xvfb and xdotool (the window tests), the test packages and Ray
#                         (the render farm, which the tests run on a local cluster); pathtrace
#                         is installed editable, so that `import pathtrace` is this checkout
set -euo pipefail
cd "$(dirname "$0")"

dev=0
[ "${1:-}" = "--dev" ] && dev=1

# pocl-opencl-icd: OpenCL on the CPU, used where no GPU driver is installed (the PoCL inside
# pyopencl's wheel fails on some CPUs; Debian's works). The GL/EGL libraries serve the viewer.
packages="python3-venv pocl-opencl-icd ocl-icd-libopencl1 libgl1 libegl1 libgl1-mesa-dri"
[ $dev = 1 ] && packages="$packages xvfb xauth xdotool x11-utils"

missing=""
for p in $packages; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
    echo "installing Debian packages:$missing"
    sudo=""
    [ "$(id -u)" = 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing
fi

[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
if [ $dev = 1 ]; then
    .venv/bin/python -m pip install -q -e ".[test,farm]"
else
    .venv/bin/python -m pip install -q .
fi
# builds the generic kernels on each device and renders with them once, so that the drivers'
# caches hold them before the first `pathtrace view` (app/device/programs.py)
if .venv/bin/pathtrace devices --check; then
    echo "pathtrace installed: .venv/bin/pathtrace"
else
    echo "pathtrace installed: .venv/bin/pathtrace, but it renders nothing until an OpenCL device builds its kernels (see above)"
fi
