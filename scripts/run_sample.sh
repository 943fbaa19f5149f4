#!/usr/bin/env bash
# The main job on the bundled sample: install what is missing, build, convert
# the PySPH dam break to .sluice, show what is inside, and decode every frame
# (verify prints the decode rate).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/deps.sh"
"$root/scripts/build.sh"
sluice="$root/build/apps/sluice/sluice"
out=${OUT_DIR:-$root/build/sample}
mkdir -p "$out"
"$sluice" convert "$root/data/dam_break_3d/dam_break_3d.pvd" -o "$out/dam_break_3d.sluice" --attribute rho --force
"$sluice" info "$out/dam_break_3d.sluice"
"$sluice" verify "$out/dam_break_3d.sluice"
