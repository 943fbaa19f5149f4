#!/usr/bin/env bash
# The main job on the bundled sample: install what is missing, build, convert
# the PySPH dam break to .sluice, show what is inside, decode every frame
# (verify prints the decode rate), render it to PNG images headless, and play
# it in a window where there is a display.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/deps.sh"
# What this script runs, not the tests and benchmarks (scripts/test.sh builds
# those): the sluice command, its import worker, and the Python module where
# it is built.
targets=(sluice sluice_import_worker)
CONFIGURE_ONLY=1 "$root/scripts/build.sh"
if grep -q '^SLUICE_PYTHON:BOOL=ON' "${BUILD_DIR:-$root/build}/CMakeCache.txt"; then targets+=(sluice_python); fi
cmake --build "${BUILD_DIR:-$root/build}" -j "${JOBS:-$(nproc)}" --target "${targets[@]}"
sluice="$root/build/apps/sluice/sluice"
out=${OUT_DIR:-$root/build/sample}
mkdir -p "$out"
"$sluice" convert "$root/data/dam_break_3d/dam_break_3d.pvd" -o "$out/dam_break_3d.sluice" --attribute rho --force
"$sluice" info "$out/dam_break_3d.sluice"
"$sluice" verify "$out/dam_break_3d.sluice"
"$sluice" play --headless --quiet "$out/dam_break_3d.sluice"
if "$sluice" render --help >/dev/null 2>&1; then
  "$sluice" render "$out/dam_break_3d.sluice" --out "$out/frames" --size 1280x720 --force
  echo "images: $out/frames/"
  if [[ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ]]; then
    "$sluice" play "$out/dam_break_3d.sluice"
  else
    echo "no display: to watch it, run  $sluice play $out/dam_break_3d.sluice  on a desktop"
  fi
fi
