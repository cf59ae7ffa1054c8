#!/usr/bin/env bash
# Installs every Debian 12 package CementSPH uses. Idempotent; run as root or with sudo.
# This is the one place the project's install list lives (README, .ci/run and developers all call it).
set -euo pipefail

PACKAGES=(
  # toolchain; ccache makes rebuilds and CI's clean clones cheap (scripts/build.sh and ci-sanitizers.sh use it
  # where present: without it CI's cold build and sanitizer tree take about an hour on the 2-core machine)
  cmake g++ make pkg-config ccache
  # core numerics
  libeigen3-dev
  # imaging and visualisation
  libvtk9-dev libinsighttoolkit5-dev libgdcm-tools libtbb-dev
  # registration reference for the imaging benchmark (issue 3)
  elastix
  # DRR reference for the DRR benchmark (issue 5): `plastimatch drr -i exact`
  plastimatch
  # tests, benchmarks, command line, JSON
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev
  # derivative-free optimisation for `cementsph plan` (issue 13)
  libnlopt-dev
  # the gzip of the NRRD volumes written (Modules/Imaging/IO/src/NrrdGzip.h)
  libdeflate-dev
  # studies and plans spread over ranks under mpirun (issue 13): Open MPI
  openmpi-bin libopenmpi-dev
  # off-screen rendering with no X server: OSMesa first, Mesa's surfaceless EGL where it fails
  # (Modules/Rendering/OffScreen/include/cementsph/rendering/RenderBackend.h)
  libosmesa6-dev libegl-mesa0 libgl1-mesa-dri
  # the last fallback if neither OSMesa nor EGL gives a context: a private virtual X server
  xvfb xauth
  # the cementsph Python module (Python/, issue 22): pybind11, Python's headers, numpy for its arrays
  # (python3-vtk9, for VTK objects in Python, comes with libvtk9-dev)
  pybind11-dev python3-dev python3-numpy
  # the sanitizer and fuzzing stage (scripts/ci-sanitizers.sh, issues 21 and 24): clang, its libFuzzer and
  # sanitizer runtimes, its OpenMP, and zlib's headers (the header checks are compiled directly)
  clang-14 libclang-rt-14-dev libomp-14-dev zlib1g-dev
)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "install-deps.sh: must run as root or with sudo available" >&2; exit 1; fi
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps.sh: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

echo "install-deps.sh: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
