#!/usr/bin/env bash
# Generate real SPH sample data with PySPH (Debian package python3-pysph):
# the 3D dam break example (pysph.examples.dam_break_3d), exported to VTK
# (.vtu) with PySPH's own `dump_vtk`. Only the fluid files (*_fluid_*.vtu)
# are kept.
#
# Defaults reproduce the bundled sample in data/dam_break_3d:
#   scripts/make_pysph_sample.sh
# A larger, uncommitted benchmark set, for example:
#   nice -n 19 scripts/make_pysph_sample.sh --dx 0.02 --tf 0.1 --pfreq 50 \
#       --out /work/bigdata/dam_break_3d_dx002
#
# Options:
#   --dx DX          particle spacing in m          (default 0.04)
#   --tf TF          final simulated time in s      (default 0.25)
#   --pfreq N        write an output every N steps  (default 50; the final
#                    time is always written as well)
#   --every K        keep only every K-th written frame (default 1 = all)
#   --out DIR        destination of the fluid .vtu files
#                    (default <repo>/data/dam_break_3d)
#   --work DIR       scratch folder for the HDF5 and VTK output
#                    (default: a fresh temporary folder, removed afterwards)
#   --keep-work      do not remove the scratch folder
#   --no-gid         run the stock example through `pysph.tools.cli run`
#                    and export only rho,p (see "Particle ids" below)
#
# Particle ids: serial PySPH never assigns `gid` (every particle keeps
# 4294967295, i.e. (uint32)-1). By default this script therefore runs the
# stock example class DamBreak3D through a 10-line driver that only sets
# gid = 0..n-1 on each particle array after creation; PySPH then carries gid
# with the particles, and dump_vtk exports it (`-s rho,p,gid`). The physics,
# parameters and output are otherwise identical to
#   python3 -m pysph.tools.cli run dam_break_3d --no-openmp --dx .. --tf .. --pfreq ..
#
# Runs on one core (--no-openmp, OMP_NUM_THREADS=1). Needs Debian 12 with
# python3-pysph, python3-h5py and mayavi2 (for dump_vtk's TVTK writer);
# these are installed with apt-get when missing (needs root or sudo).
# This script installs nothing else and does not call sluice.
set -euo pipefail

PY=/usr/bin/python3
SCRIPT_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
REPO_ROOT=$(cd "$SCRIPT_DIR/.." && pwd)

DX=0.04
TF=0.25
PFREQ=50
EVERY=1
OUT="$REPO_ROOT/data/dam_break_3d"
WORK=""
KEEP_WORK=0
WITH_GID=1

usage() { sed -n '2,/^set -euo/p' "$0" | grep '^#' | sed 's/^# \{0,1\}//'; }

while [[ $# -gt 0 ]]; do
    case "$1" in
        --dx) DX="$2"; shift 2 ;;
        --tf) TF="$2"; shift 2 ;;
        --pfreq) PFREQ="$2"; shift 2 ;;
        --every) EVERY="$2"; shift 2 ;;
        --out) OUT="$2"; shift 2 ;;
        --work) WORK="$2"; shift 2 ;;
        --keep-work) KEEP_WORK=1; shift ;;
        --no-gid) WITH_GID=0; shift ;;
        -h|--help) usage; exit 0 ;;
        *) echo "make_pysph_sample: unknown argument: $1" >&2; usage >&2; exit 2 ;;
    esac
done

log() { printf '[make_pysph_sample %s] %s\n' "$(date +%H:%M:%S)" "$*"; }

# --- 1. packages, only the missing ones ------------------------------------
missing=()
for pkg in python3-pysph python3-h5py mayavi2; do
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$pkg")
    fi
done
if [[ ${#missing[@]} -gt 0 ]]; then
    log "installing missing packages: ${missing[*]}"
    SUDO=""
    if [[ $(id -u) -ne 0 ]]; then
        command -v sudo >/dev/null || { echo "need root or sudo to install ${missing[*]}" >&2; exit 1; }
        SUDO=sudo
    fi
    $SUDO apt-get update
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
else
    log "packages present: python3-pysph python3-h5py mayavi2"
fi
log "PySPH package: $(dpkg-query -W -f='${Package} ${Version}' python3-pysph)"

# --- 2. scratch folder ------------------------------------------------------
if [[ -z "$WORK" ]]; then
    WORK=$(mktemp -d "${TMPDIR:-/tmp}/pysph_dam_break_3d.XXXXXX")
    if [[ $KEEP_WORK -eq 0 ]]; then
        trap 'rm -rf "$WORK"' EXIT
    fi
fi
mkdir -p "$WORK"
SIM_DIR="$WORK/sim"
VTK_DIR="$WORK/vtk"
rm -rf "$SIM_DIR" "$VTK_DIR"
log "scratch folder: $WORK"

# One core only.
export OMP_NUM_THREADS=1
# dump_vtk goes through TVTK/mayavi; no GUI toolkit is needed to write files.
export ETS_TOOLKIT=null

# --- 3. simulate ------------------------------------------------------------
SIM_OPTS=(--no-openmp --dx "$DX" --tf "$TF" --pfreq "$PFREQ" -d "$SIM_DIR")
if [[ $WITH_GID -eq 1 ]]; then
    SCALARS="rho,p,gid"
    DRIVER="$WORK/dam_break_3d_gid.py"
    cat > "$DRIVER" <<'PYEOF'
# PySPH's stock dam_break_3d example; the only change: gid = 0..n-1.
import numpy as np
from pysph.examples.dam_break_3d import DamBreak3D


class DamBreak3DWithGid(DamBreak3D):
    def create_particles(self):
        arrays = super().create_particles()
        for pa in arrays:
            n = pa.get_number_of_particles()
            pa.gid[:] = np.arange(n, dtype=np.uint32)
        return arrays


if __name__ == '__main__':
    DamBreak3DWithGid(fname='dam_break_3d').run()
PYEOF
    RUN_CMD=("$PY" "$DRIVER" "${SIM_OPTS[@]}")
else
    SCALARS="rho,p"
    RUN_CMD=("$PY" -m pysph.tools.cli run dam_break_3d "${SIM_OPTS[@]}")
fi
log "running: ${RUN_CMD[*]}"
t0=$(date +%s)
"${RUN_CMD[@]}"
t1=$(date +%s)
log "simulation took $((t1 - t0)) s"

# --- 4. export to VTK -------------------------------------------------------
VTK_CMD=("$PY" -m pysph.tools.cli dump_vtk -s "$SCALARS" -d "$VTK_DIR" "$SIM_DIR")
log "running: ${VTK_CMD[*]}"
"${VTK_CMD[@]}"
t2=$(date +%s)
log "dump_vtk took $((t2 - t1)) s"

# --- 5. copy the fluid files ------------------------------------------------
mapfile -t fluid < <(find "$VTK_DIR" -maxdepth 1 -name '*_fluid_*.vtu' -printf '%f\n' | sort -V)
if [[ ${#fluid[@]} -eq 0 ]]; then
    echo "make_pysph_sample: dump_vtk produced no *_fluid_*.vtu files in $VTK_DIR" >&2
    exit 1
fi
mkdir -p "$OUT"
# Remove fluid files of an earlier run so frames do not mix.
find "$OUT" -maxdepth 1 -name '*_fluid_*.vtu' -delete
kept=0
for i in "${!fluid[@]}"; do
    if (( i % EVERY == 0 )); then
        cp "$VTK_DIR/${fluid[$i]}" "$OUT/"
        kept=$((kept + 1))
    fi
done
log "copied $kept of ${#fluid[@]} fluid frames to $OUT"

# --- 6. a .pvd series with the simulation times --------------------------------
# dump_vtk writes no time into the .vtu files; the HDF5 output has it
# (solver_data/t). The .pvd lets `sluice convert` carry real times.
PVD="$OUT/dam_break_3d.pvd"
"$PY" - "$SIM_DIR" "$OUT" "$PVD" <<'PYEOF'
import glob, os, re, sys
import h5py
sim, out, pvd = sys.argv[1:4]
times = {}
for h5 in glob.glob(os.path.join(sim, '*.hdf5')):
    with h5py.File(h5, 'r') as f:
        times[int(re.search(r'_(\d+)\.hdf5$', h5).group(1))] = float(f['solver_data'].attrs['t'])
rows = []
for vtu in sorted(glob.glob(os.path.join(out, '*_fluid_*.vtu'))):
    it = int(re.search(r'_(\d+)\.vtu$', vtu).group(1))
    rows.append('    <DataSet timestep="%.9g" part="0" file="%s"/>' % (times[it], os.path.basename(vtu)))
with open(pvd, 'w') as f:
    f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n')
    f.write('\n'.join(rows) + '\n  </Collection>\n</VTKFile>\n')
print('wrote %s (%d frames)' % (pvd, len(rows)))
PYEOF
# Print the run's info file (solver parameters, times) for the record.
info=$(find "$SIM_DIR" -maxdepth 1 -name '*.info' | head -n 1)
[[ -n "$info" ]] && log "run info: $(cat "$info")"
du -sh "$OUT"
log "total $(( $(date +%s) - t0 )) s"
