#!/usr/bin/env bash
# Installs the Debian 12 packages organsim needs to build and test.
# Idempotent: packages already present are skipped, so it is cheap to re-run.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config
  libcgal-dev libeigen3-dev libcli11-dev nlohmann-json3-dev
  # Google Highway: the CPU kernel's SIMD for every instruction set.
  libhwy-dev
  # Labelled images (segmentations) for `organsim mesh`: NIfTI-1 through
  # libniftiio (libnifti2-dev brings it, its nifti1.h and znzlib), NRRD
  # through teem; CGAL ImageIO (in libcgal-dev) reads .inr.
  libnifti2-dev libteem-dev zlib1g-dev
  libgtest-dev
  libegl-dev libgl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri
  # OpenCV: the four module packages only (~254 MB instead of ~825 MB for
  # libopencv-dev); they ship no OpenCVConfig.cmake, CMake finds them by hand.
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-videoio-dev
  # Real-world CC0 meshes (femur, bunny, ...) used by some tests.
  libcgal-demo
  # VTK itself (Python bindings, run as /usr/bin/python3): tests read the
  # .vtu/.vtp/.pvd files we write with it and read files it writes.
  python3-vtk9
  # A one-node Slurm cluster for the sweep's job-array test (tests/slurm):
  # the daemons and sbatch, and munge, which signs Slurm's messages.
  slurm-wlm munge
  # OpenIGTLink for `organsim serve` (igtl/), and the upstream example
  # programs as source (the live tests build TrackerClient from them).
  libopenigtlink-dev openigtlink-examples
  # Fuzzing (scripts/fuzz.sh): clang's libFuzzer runtime and its OpenMP.
  clang-14 libclang-rt-14-dev libomp-14-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages already installed"
  exit 0
fi

echo "setup: installing ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
