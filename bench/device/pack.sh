#!/usr/bin/env bash
# Packs what the GPU machine needs (it starts bare, with another OS): the
# sluice binary, every shared library it links that is not glibc, a few
# frames of the larger PySPH run, and the Vulkan loader packages.
# Output: .gpu/ (ignored by git), carried by the device tool.
#   [BASE=other/sluice] [VTK_PEER=PREFIX/bin/vtk_fluid_peer] bash bench/device/pack.sh [BIG_VTU_DIR]
# BIG_VTU_DIR: a folder of solver-sized .vtu frames for the `io` stage (e.g.
# PySPH's dam break at --dx 0.02, ../shared/DATA.md); without it none are packed.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
big=${1:-}
stage=$(mktemp -d)
mkdir -p "$stage/lib" "$stage/big" "$root/.gpu"
ldd "$root/build/apps/sluice/sluice" | awk '{print $3}' | grep '^/' |
  grep -v -E '/(libc|libm|libpthread|libdl|libgcc_s|libstdc\+\+)\.so|ld-linux' | xargs -I{} cp -L {} "$stage/lib/"
if [[ -n "$big" && -d "$big" ]]; then
  ls "$big"/*.vtu | sort -V | awk 'NR % 4 == 0' | head -6 | xargs -I{} cp {} "$stage/big/"
fi
tar -C "$stage" -cf - lib big | xz -6 -T2 > "$root/.gpu/pack.tar.xz"
cp "$root/build/apps/sluice/sluice" "$root/.gpu/sluice"
# A second binary to measure side by side in the same run (e.g. the last release): BASE=path/to/sluice.
if [[ -n "${BASE:-}" ]]; then cp "$BASE" "$root/.gpu/sluice_base"; else rm -f "$root/.gpu/sluice_base"; fi
# The native VTK peer (bench/vtk_peer/build.sh), for the vtkpeer stage: VTK_PEER=PREFIX/bin/vtk_fluid_peer.
if [[ -n "${VTK_PEER:-}" ]]; then cp "$VTK_PEER" "$root/.gpu/vtk_fluid_peer"; else rm -f "$root/.gpu/vtk_fluid_peer"; fi
rm -rf "$stage"
# Vulkan loader (the driver is the machine's own).
mkdir -p "$root/.gl" /tmp/amd64/partial
o=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64)
if ! ls "$root"/.gl/libglvnd0_*.deb >/dev/null 2>&1; then
  apt-get "${o[@]}" update -qq
  # glvnd too: without it the H200 box's libGLX_nvidia gives the loader no
  # vkCreateInstance (ErrorIncompatibleDriver).
  (cd "$root/.gl" && apt-get "${o[@]}" download libvulkan1 libwayland-client0 libx11-6 libxcb1 libxau6 libxdmcp6 \
    libbsd0 libmd0 libffi8 vulkan-tools libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi
du -sh "$root/.gpu" "$root/.gl"
