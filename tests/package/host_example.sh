#!/usr/bin/env bash
# The installed package as a host app uses it: install this build into a
# scratch prefix, build examples/host_vulkan against it with
# find_package(sluice) (nothing from the source tree), run it on the local
# Vulkan device and let it check the occlusion both ways.
# Usage: host_example.sh BUILD_DIR SOURCE_DIR SCRATCH_DIR [SANITIZERS]
set -euo pipefail
build=$1 src=$2 scratch=$3 sanitize=${4:-}
rm -rf "$scratch" && mkdir -p "$scratch"
cmake --install "$build" --prefix "$scratch/prefix" >/dev/null
flags=()
if [[ -n "$sanitize" ]]; then
  flags=(-DCMAKE_CXX_FLAGS="-fsanitize=$sanitize -fno-omit-frame-pointer" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=$sanitize")
fi
# GLFW and OpenXR hidden: a host that asks for the render component only
# must configure without them.
hidden=(-DCMAKE_DISABLE_FIND_PACKAGE_glfw3=ON -DCMAKE_DISABLE_FIND_PACKAGE_OpenXR=ON)
cmake -S "$src/examples/host_vulkan" -B "$scratch/build" -DCMAKE_PREFIX_PATH="$scratch/prefix" "${hidden[@]}" \
  -DCMAKE_BUILD_TYPE=Release "${flags[@]}" >/dev/null
# The host as host authors build it, each against the same (Release)
# package: as the README says (no build type: no NDEBUG), Debug with the
# standard library's assertions, and Debug under ASan + UBSan. Vulkan-Hpp's
# debug layout must not meet sluice's (cmake/vulkan_hpp.cmake).
declare -A variants=(
  [readme]=""
  [debug]="-DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS=-D_GLIBCXX_ASSERTIONS"
  [asan]="-DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS=-fsanitize=address,undefined -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined"
)
for v in readme debug asan; do
  # shellcheck disable=SC2086 # the variant's flags are words
  cmake -S "$src/examples/host_vulkan" -B "$scratch/build-$v" -DCMAKE_PREFIX_PATH="$scratch/prefix" "${hidden[@]}" \
    ${variants[$v]} >/dev/null
  cmake --build "$scratch/build-$v" -j 2 >/dev/null
done
# Asked for, the optional components load (their dependencies are there).
mkdir -p "$scratch/components"
cat > "$scratch/components/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(components LANGUAGES CXX)
find_package(sluice REQUIRED COMPONENTS render stream desktop xr)
foreach(t sluice::render sluice::stream sluice::desktop sluice::xr)
  if(NOT TARGET ${t})
    message(FATAL_ERROR "${t} missing")
  endif()
endforeach()
CMAKE
cmake -S "$scratch/components" -B "$scratch/components/build" -DCMAKE_PREFIX_PATH="$scratch/prefix" >/dev/null
# And hidden, asking for desktop fails.
if cmake -S "$scratch/components" -B "$scratch/components/hidden" -DCMAKE_PREFIX_PATH="$scratch/prefix" \
     -DCMAKE_DISABLE_FIND_PACKAGE_glfw3=ON >/dev/null 2>&1; then
  echo "find_package(sluice COMPONENTS desktop) succeeded without GLFW"; exit 1
fi
# A misspelt component is named; io alone needs no Vulkan and defines no render target.
mkdir -p "$scratch/only"
cat > "$scratch/only/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(only LANGUAGES CXX)
find_package(sluice REQUIRED COMPONENTS ${WANT})
if(NOT TARGET sluice::io OR TARGET sluice::render)
  message(FATAL_ERROR "COMPONENTS ${WANT}: expected sluice::io and no sluice::render")
endif()
CMAKE
if cmake -S "$scratch/only" -B "$scratch/only/misspelt" -DCMAKE_PREFIX_PATH="$scratch/prefix" -DWANT=renderr \
     >"$scratch/only/misspelt.log" 2>&1 || ! grep -q "no component 'renderr'" "$scratch/only/misspelt.log"; then
  echo "find_package(sluice COMPONENTS renderr) did not fail naming renderr:"; cat "$scratch/only/misspelt.log"; exit 1
fi
cmake -S "$scratch/only" -B "$scratch/only/io" -DCMAKE_PREFIX_PATH="$scratch/prefix" -DWANT=io \
  -DCMAKE_DISABLE_FIND_PACKAGE_Vulkan=ON -DCMAKE_DISABLE_FIND_PACKAGE_PNG=ON >/dev/null
cmake --build "$scratch/build" -j 2 >/dev/null
# Conversion as a library call: a host program linking sluice::import alone,
# VTK's readers in the installed worker processes.
mkdir -p "$scratch/convert"
cat > "$scratch/convert/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(convert LANGUAGES CXX)
set(CMAKE_CXX_STANDARD 20)
find_package(sluice REQUIRED COMPONENTS import)
add_executable(convert convert.cpp)
target_link_libraries(convert PRIVATE sluice::import)
target_compile_definitions(convert PRIVATE WORKER="${SLUICE_IMPORT_WORKER}")
CMAKE
cat > "$scratch/convert/convert.cpp" <<'CPP'
#include <cstdio>
#include "sluice/import/convert.h"
int main(int argc, char** argv) {
  if (argc != 3) return 2;
  sluice::import::ConvertOptions options;
  options.input = argv[1];
  options.isolation.worker = WORKER;
  uint64_t progressed = 0;
  sluice::import::ConvertObserver observer;
  observer.progressed = [&](const sluice::import::ConvertProgress& p) { progressed = p.frames_done; };
  const sluice::import::ConvertSummary s = sluice::import::convert(options, argv[2], observer);
  std::printf("%llu frames, %llu particles, progress to %llu\n", (unsigned long long)s.frames,
              (unsigned long long)s.particles, (unsigned long long)progressed);
  return s.frames == progressed && s.frames > 0 ? 0 : 1;
}
CPP
cmake -S "$scratch/convert" -B "$scratch/convert/build" -DCMAKE_PREFIX_PATH="$scratch/prefix" -DCMAKE_BUILD_TYPE=Release \
  "${flags[@]}" >/dev/null
cmake --build "$scratch/convert/build" -j 2 >/dev/null
cd "$scratch"
# The bundled sample, converted by that program and streamed from its file.
"$scratch/convert/build/convert" "$src/data/dam_break_3d/dam_break_3d.pvd" "$scratch/dam.sluice"
"$scratch/build/host_vulkan" --check --frames 8 --out "$scratch/host_vulkan.png" "$scratch/dam.sluice"
for v in readme debug asan; do
  echo "--- host built: $v"
  if [[ $v == asan ]]; then
    # Twice: with synchronization validation (as the environment asks) and
    # leak checks off, then with leak checks on and synchronization
    # validation off: its state is still allocated when the loader unloads
    # the layer, reported from a module LeakSanitizer can no longer name
    # (tests/CMakeLists.txt). Lavapipe preloaded so its own leaks can be
    # named and suppressed (tests/lsan.supp).
    lvp=$(ls /usr/lib/*/libvulkan_lvp.so 2>/dev/null | head -1 || true)
    LD_PRELOAD=$lvp ASAN_OPTIONS=detect_leaks=0:verify_asan_link_order=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      "$scratch/build-$v/host_vulkan" --check --frames 8 --out "$scratch/host_$v.png" "$scratch/dam.sluice"
    env -u VK_LAYER_ENABLES LD_PRELOAD="$lvp" ASAN_OPTIONS=detect_leaks=1:verify_asan_link_order=0 \
      UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 LSAN_OPTIONS=suppressions=$src/tests/lsan.supp \
      "$scratch/build-$v/host_vulkan" --check --frames 8 --out "$scratch/host_$v.png" "$scratch/dam.sluice"
  else
    "$scratch/build-$v/host_vulkan" --check --frames 8 --out "$scratch/host_$v.png" "$scratch/dam.sluice"
  fi
done
# docs/embedding.md's host program (cut out of the page by tests/docs at
# configure time) built against the installed package alone, drawing each
# frame of the sample once under the validation layer (enabled from the
# environment: the program has no messenger, the layer prints what it finds).
mkdir -p "$scratch/docs_host"
cp "$build/tests/docs/docs_host.cpp" "$scratch/docs_host/"
cat > "$scratch/docs_host/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(docs_host LANGUAGES CXX)
set(CMAKE_CXX_STANDARD 20)
find_package(sluice REQUIRED COMPONENTS stream)
add_executable(docs_host docs_host.cpp)
target_link_libraries(docs_host PRIVATE sluice::stream)
CMAKE
cmake -S "$scratch/docs_host" -B "$scratch/docs_host/build" -DCMAKE_PREFIX_PATH="$scratch/prefix" "${hidden[@]}" >/dev/null
cmake --build "$scratch/docs_host/build" -j 2 >/dev/null
VK_INSTANCE_LAYERS=VK_LAYER_KHRONOS_validation "$scratch/docs_host/build/docs_host" "$scratch/dam.sluice" \
  "$scratch/docs_host/frame_" 2>&1 | tee "$scratch/docs_host/run.log"
if grep -q -i "validation\|VUID" "$scratch/docs_host/run.log"; then echo "docs_host: validation messages"; exit 1; fi
test "$(ls "$scratch"/docs_host/frame_*.png | wc -l)" -eq "$("$build/apps/sluice/sluice" info --json "$scratch/dam.sluice" |
  /usr/bin/python3 -c 'import json, sys; print(len(json.load(sys.stdin)["frames"]))')"
# The same host pushing frames of its own simulation (stream::LiveSource), recorded as it goes.
"$scratch/build/host_vulkan" --live --check --frames 6 --record "$scratch/live.sluice" --out "$scratch/host_live.png"
test -s "$scratch/live.sluice"
# The Python module as installed (where built): importable from the prefix's
# site directory, reading what the host recorded.
site=$(ls -d "$scratch"/prefix/lib/python3*/dist-packages 2>/dev/null | head -1 || true)
if [[ -n "$site" ]]; then
  PYTHONPATH="$site" /usr/bin/python3 -c "import sluice, sys; s = sluice.open(sys.argv[1]); assert len(s) == 6 and len(s[5]) > 0, len(s)" \
    "$scratch/live.sluice"
  echo "installed python module: ok"
fi
