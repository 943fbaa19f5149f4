#!/usr/bin/env bash
# Builds the native VTK peer (vtk_fluid_peer) against VTK 9.1 from Debian 12's
# source package, with EGL and without X, so that vtkOpenGLFluidMapper runs
# headless on a GPU driver (the GPU machine has no X server). Only the modules
# the fluid mapper needs are built (22 static libraries, ~1,250 build steps;
# 32 minutes on 2 cores with a cold ccache), and linked statically into one
# binary: what the GPU machine needs besides it is glvnd's libEGL/libOpenGL
# (bench/device/pack.sh carries them) and the driver's own EGL vendor library.
#   bash bench/vtk_peer/build.sh PREFIX   -> PREFIX/bin/vtk_fluid_peer (reused when present)
# Then: sluice bench render --vtk --vtk-peer PREFIX/bin/vtk_fluid_peer ...
#
# Why GLEW is rebuilt: Debian strips VTK's vendored GLEW, and Debian's libglew
# is built for GLX, whose glewInit() fails without an X display. GLEW's one
# source file, from Debian's glew source package, is compiled with GLEW_EGL.
set -euo pipefail
prefix=${1:?usage: build.sh PREFIX}
prefix=$(realpath -m "$prefix")
here=$(cd "$(dirname "$0")" && pwd)
jobs=${JOBS:-$(nproc)}
if [[ -x "$prefix/bin/vtk_fluid_peer" && "$prefix/bin/vtk_fluid_peer" -nt "$here/vtk_fluid_peer.cpp" ]]; then
  echo "vtk_fluid_peer: $prefix/bin/vtk_fluid_peer (built earlier)"
  exit 0
fi

packages=(build-essential cmake ninja-build ccache dpkg-dev libegl-dev libopengl-dev libglvnd-dev
          libdouble-conversion-dev libutfcpp-dev liblz4-dev liblzma-dev zlib1g-dev libexpat1-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
sudo=()
[[ $(id -u) -eq 0 ]] || sudo=(sudo)
if [[ ${#missing[@]} -gt 0 ]]; then
  echo "build.sh: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Debian 12's sources through a private apt configuration (the system's is not touched).
src=$prefix/src
mkdir -p "$src/apt/lists/partial" "$src/apt/cache/archives/partial"
source "$(dirname "${BASH_SOURCE[0]}")/../../scripts/debian_mirrors.sh"
debian_source_list bookworm > "$src/apt/sources.list"
o=(-o "Dir::Etc::SourceList=$src/apt/sources.list" -o Dir::Etc::SourceParts=/dev/null
   -o "Dir::State::Lists=$src/apt/lists" -o "Dir::Cache=$src/apt/cache")
if [[ ! -d "$src/vtk9" || ! -d "$src/glew" ]]; then
  apt-get "${o[@]}" update -qq 2>&1 | grep -v unsandboxed || true
  # apt checks the tarballs against the signed index; dpkg-source applies Debian's patches.
  (cd "$src" && rm -rf vtk9 glew && apt-get "${o[@]}" source -qq vtk9 glew 2>&1 | grep -v unsandboxed || true)
  (cd "$src" && mv "$(ls -d vtk9-*/ | head -1)" vtk9 && mv "$(ls -d glew-*/ | head -1)" glew)
fi

mkdir -p "$prefix/glew/lib" "$prefix/glew/include"
gcc -O2 -fPIC -w -DGLEW_EGL -DGLEW_NO_GLU -DGLEW_STATIC -I"$src/glew/include" -c "$src/glew/src/glew.c" -o "$prefix/glew/glew.o"
ar rcs "$prefix/glew/lib/libGLEW.a" "$prefix/glew/glew.o"
cp -r "$src/glew/include/GL" "$prefix/glew/include/"

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
external=()
for m in utf8 doubleconversion lz4 lzma zlib expat png jpeg tiff freetype eigen jsoncpp; do
  external+=(-DVTK_MODULE_USE_EXTERNAL_VTK_$m=ON)
done
cmake -S "$(realpath "$src/vtk9")" -B "$prefix/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DBUILD_SHARED_LIBS=OFF \
  "${launcher[@]}" -DCMAKE_POSITION_INDEPENDENT_CODE=ON -DCMAKE_INSTALL_PREFIX="$prefix/vtk" \
  -DVTK_BUILD_TESTING=OFF -DVTK_BUILD_EXAMPLES=OFF -DVTK_WRAP_PYTHON=OFF -DVTK_WRAP_JAVA=OFF -DVTK_ENABLE_REMOTE_MODULES=OFF \
  -DVTK_GROUP_ENABLE_StandAlone=DONT_WANT -DVTK_GROUP_ENABLE_Rendering=DONT_WANT -DVTK_BUILD_ALL_MODULES=OFF \
  -DVTK_MODULE_ENABLE_VTK_RenderingOpenGL2=YES \
  -DVTK_OPENGL_HAS_EGL=ON -DVTK_USE_X=OFF -DVTK_DEFAULT_RENDER_WINDOW_OFFSCREEN=ON -DOpenGL_GL_PREFERENCE=GLVND \
  -DVTK_SMP_IMPLEMENTATION_TYPE=Sequential "${external[@]}" \
  -DVTK_MODULE_USE_EXTERNAL_VTK_glew=ON -DGLEW_INCLUDE_DIR="$prefix/glew/include" -DGLEW_LIBRARY="$prefix/glew/lib/libGLEW.a" \
  -DCMAKE_C_FLAGS=-DGLEW_STATIC -DCMAKE_CXX_FLAGS=-DGLEW_STATIC >/dev/null
cmake --build "$prefix/build" -j "$jobs"
cmake --install "$prefix/build" >/dev/null

cmake -S "$here" -B "$prefix/peer-build" -DCMAKE_BUILD_TYPE=Release -DVTK_DIR="$prefix/vtk/lib/cmake/vtk-9.1" \
  -DGLEW_INCLUDE_DIR="$prefix/glew/include" -DGLEW_LIBRARY="$prefix/glew/lib/libGLEW.a" >/dev/null
cmake --build "$prefix/peer-build" -j "$jobs"
mkdir -p "$prefix/bin"
cp "$prefix/peer-build/vtk_fluid_peer" "$prefix/bin/"
strip "$prefix/bin/vtk_fluid_peer"
echo "vtk_fluid_peer: $prefix/bin/vtk_fluid_peer"
