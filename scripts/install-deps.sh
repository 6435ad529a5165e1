#!/usr/bin/env bash
# Install the Debian packages meso needs to build, test and benchmark.
# Idempotent: packages already installed are skipped, so `make test` can call it every time.
set -euo pipefail

packages=(
    build-essential cmake pkg-config
    libpng-dev            # images
    libstb-dev            # Radiance .hdr environment maps (stb_image)
    libcjson-dev          # scene files
    libassimp-dev         # mesh import
    assimp-testmodels     # make test-assets: assimp's own corpus of models nobody here made
    libembree-dev         # reference ray tracer (Embree 3)
    liblapacke-dev libopenblas-dev   # SVD (VDM / GDM compression)
    libcmocka-dev         # tests
    libopenexr-dev        # .exr outputs (OpenEXRCore's C API)
    libcairo2-dev fonts-dejavu-core   # labels of sheets and plots (DejaVu Sans Mono)
    clang libclang-rt-14-dev libomp-dev   # make test-clang (UBSan, float-cast-overflow), fuzzing
    clang-format          # make format-check (CI)
    libsdl2-dev           # meso view (optional: without it the viewer is not built)
    python3-numpy python3-pil   # the docs' measuring scripts (scripts/error_bands.py)
    libegl-dev libepoxy-dev     # the OpenGL back end: EGL headless, GL entry points
    libegl-mesa0 libgl1-mesa-dri   # Mesa's EGL and llvmpipe: GL 3.3 core without a GPU
    glslang-tools         # glslangValidator checks shaders/ in make test
    libopenexr-dev        # meso bake -o: VDM tables as OpenEXR
    python3-cffi python3-dev python3-setuptools   # the Python package (python/, cffi API mode)
    python3-numpy python3-pytest python3-matplotlib   # its tests and examples (docs/python.md)
    munge slurmctld slurmd slurm-client   # make test-slurm: a one-node Slurm cluster
    chromium              # the sweep report's test: index.html in headless Chromium
)

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
sudo=""
if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "install-deps: not root and no sudo; install: ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
