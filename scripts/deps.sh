#!/usr/bin/env bash
# Installs the Debian 12 packages sluice needs to build and test, skipping
# those already present. Runs apt-get as root, or through sudo.
set -euo pipefail

packages=(
  build-essential cmake pkg-config ccache git
  libzstd-dev libtbb-dev libxxhash-dev libcli11-dev libvtk9-dev zlib1g-dev
  libgtest-dev libbenchmark-dev
  python3-dev pybind11-dev python3-numpy python3-pytest python3-matplotlib
  mypy  # the Python module's stubs checked against the examples (python.stubs)
  clang libclang-rt-14-dev
  openmpi-bin libopenmpi-dev  # convert --mpi, and its test under mpirun
)
# The renderer's packages, when the tree has a renderer.
if [[ -d "$(dirname "$0")/../render/src" ]]; then
  packages+=(libvulkan-dev glslc mesa-vulkan-drivers vulkan-validationlayers libglfw3-dev libimgui-dev
             libpng-dev xvfb xauth libopenxr-dev libopenxr-loader1
             ffmpeg)  # render --out x.mp4, and its tests (a full disk, a video read back)
fi
# ParaView's libraries for the reader plugin (its headers, CMake files and
# pvpython are unpacked by scripts/paraview.sh: they cannot be installed
# beside libvtk9-dev).
if [[ -d "$(dirname "$0")/../paraview" ]]; then
  packages+=(paraview)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [[ ${#missing[@]} -eq 0 ]]; then
  echo "deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "deps: installing ${missing[*]}"
sudo=()
[[ $(id -u) -eq 0 ]] || sudo=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
