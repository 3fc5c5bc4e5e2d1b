#!/usr/bin/env bash
# Installs the Debian 12 packages ssslab needs. As root it installs what is missing; otherwise it
# prints the exact apt-get line to run and exits non-zero if anything is missing.
#
#   scripts/setup.sh          build and test dependencies
#   scripts/setup.sh --dev    also the developer tools CI uses (clang-format, Clang and libFuzzer)
set -euo pipefail

packages=(
  build-essential cmake ninja-build git pkg-config
  libtbb-dev            # oneTBB: parallel photon batches and kernel builds
  libeigen3-dev         # Eigen: dense linear algebra of the kernel models
  libspectra-dev        # Spectra: leading eigenpairs only (truncated SVD of large kernels)
  libfftw3-dev          # FFTW: exact 2D convolutions (the image-space ground truth)
  libmuparser-dev       # muparser: profile models written as expressions in TOML files (no rebuild, no GL)
  libfmt-dev            # fmt: formatting
  libcli11-dev          # CLI11: the command line
  libtomlplusplus-dev   # toml++: TOML configs with source positions for error messages
  librandom123-dev      # Random123: counter-based Philox streams
  libgtest-dev libgmock-dev  # GoogleTest
  libbenchmark-dev      # Google Benchmark: micro-benchmarks
  zlib1g-dev            # zlib: reading the gzipped MCML reference outputs in the tests
  libxxhash-dev         # xxHash: content hashes that key the artifact cache
  libopenexr-dev        # OpenEXR 3.1: layered float images with standard-error layers (directly)
  libopenimageio-dev    # OpenImageIO: PNG previews, and ssslab compare on images of any format
  openimageio-tools     # OpenImageIO's CMake config refuses to load without its tools (/usr/bin/iconvert)
  libtinyobjloader-dev  # tinyobjloader: Wavefront OBJ meshes of scene files
  libembree-dev         # Embree 3: ray queries against the meshes of scenes (path tracer)
  libopenvdb-dev libboost-iostreams-dev  # OpenVDB: heterogeneous media (optional part; FindOpenVDB needs Boost iostreams)
  libosmesa6-dev libegl-dev libegl-mesa0 libgl1-mesa-dri  # headless OpenGL (OSMesa, EGL with Mesa as its vendor; llvmpipe): the GL twin
  python3-glad          # glad2: generates the GL twin's loader at build time, offline
  libopenmpi-dev openmpi-bin  # Open MPI: runs spread over processes and machines (mpirun; optional part)
  python3-matplotlib    # plots of the experiment reports (run by Debian's /usr/bin/python3)
  pybind11-dev python3-dev python3-numpy python3-pytest  # the Python module (python/) and its tests
  chromium              # headless check that the HTML reports open and show their plots
)
if [[ "${1:-}" == "--dev" ]]; then
  packages+=(clang-format clang libclang-rt-14-dev)  # formatting; libFuzzer (scripts/fuzz.sh)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "setup: all ${#packages[@]} packages are installed"
  exit 0
fi

if [[ $(id -u) -eq 0 ]]; then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: missing packages. Run as root:"
  echo "  apt-get update && apt-get install -y --no-install-recommends ${missing[*]}"
  exit 1
fi
