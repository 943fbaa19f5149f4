#!/usr/bin/env bash
# `sluice convert --mpi` against the serial conversion (CTest mpi.convert):
#   1. byte-identical output at 1, 2 and 4 ranks, on the bundled sample and on
#      a synthetic series whose frames hold from 1,223 to 40,000 particles;
#      an output that exists is refused once (by rank 0), left as it was;
#      SLUICE_MPI_TIMELINE writes every rank's steps;
#   2. a damaged frame read on rank 2 stops every rank with the serial
#      message (and the rank), the output as the serial one keeps it;
#   3. --skip-bad under MPI gives the serial file;
#   4. a rank that dies after the first round: mpirun fails, no output file,
#      the .partial's frames recovered by `sluice recover`.
# Usage: convert_mpi.sh SLUICE WORKDIR SAMPLE_DIR
set -euo pipefail
sluice=$1 work=$2 sample=$3
rm -rf "$work" && mkdir -p "$work" && cd "$work"
as_root=(); [[ $(id -u) -eq 0 ]] && as_root=(--allow-run-as-root)
# Under ASan (scripts/test.sh), ranks check memory errors but not leaks:
# Open MPI leaks about 120 kB at exit from plugins it has unloaded, whose
# frames LeakSanitizer cannot name, so no suppression can match them alone.
# The serial conversions here keep leak checking.
rank_asan="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
# Each run has a deadline: a rank waiting forever fails the test, it does not hang it.
mpirun_() { ASAN_OPTIONS=$rank_asan timeout 180 mpirun "${as_root[@]}" --oversubscribe "$@"; }
mpi() { local n=$1; shift; mpirun_ -np "$n" "$sluice" convert --mpi "$@"; }
fail() { echo "FAIL: $*" >&2; exit 1; }
same() { cmp "$1" "$2" || fail "$2 differs from $1"; echo "ok: $2 is $1 byte for byte"; }

echo "--- 1. the bundled sample and an uneven series, 1, 2 and 4 ranks"
"$sluice" convert "$sample/dam_break_3d.pvd" -a rho -o serial_sample.sluice -q
"$sluice" synth -n 40k --frames 10 --motion lattice -o synth.sluice -q
mkdir uneven
levels=(1 0.1 0.6 0.03 0.9 0.2 1 0.05 0.4 0.7)
for i in "${!levels[@]}"; do
  "$sluice" export synth.sluice --frames "$i" --lod-level "${levels[$i]}" -o "uneven/f_$(printf %02d "$i").vtp" -q
done
"$sluice" convert 'uneven/*.vtp' -o serial_uneven.sluice -q
for n in 1 2 4; do
  mpi "$n" "$sample/dam_break_3d.pvd" -a rho -o "sample_$n.sluice" -q --jobs 1
  same serial_sample.sluice "sample_$n.sluice"
  mpi "$n" 'uneven/*.vtp' -o "uneven_$n.sluice" -q --jobs 2
  same serial_uneven.sluice "uneven_$n.sluice"
done

echo "--- 1a. SLUICE_MPI_TIMELINE: every rank's steps, every frame's encoding once"
SLUICE_MPI_TIMELINE=timeline.csv mpi 4 'uneven/*.vtp' -o uneven_timeline.sluice -q --jobs 1
same serial_uneven.sluice uneven_timeline.sluice
[[ $(head -1 timeline.csv) == "rank,step,frame,start_s,end_s" ]] || fail "timeline: no header"
for r in 0 1 2 3; do grep -q "^$r,write,-1," timeline.csv || fail "timeline: rank $r's write missing"; done
[[ $(grep -cE '^[0-3],(read and )?encode,[0-9]+,' timeline.csv) == 10 ]] || { cat timeline.csv; fail "timeline: not 10 frames encoded"; }
awk -F, 'NR > 1 && !($5 >= $4 && $4 >= 0) { exit 1 }' timeline.csv || fail "timeline: a span ends before it starts"

echo "--- 1b. an output that exists, without --force: refused once, by rank 0"
if mpi 4 "$sample/dam_break_3d.pvd" -a rho -o sample_4.sluice -q 2> exists.err; then fail "overwrote without --force"; fi
[[ $(grep -c "sample_4.sluice exists; pass --force" exists.err) == 1 ]] || { cat exists.err; fail "not said once"; }
same serial_sample.sluice sample_4.sluice

echo "--- 2. a damaged frame, read on rank 2 (4 ranks, 2 frames each a round: frames 4 and 5)"
mkdir damaged
cp "$sample"/*.vtu damaged/
bad=damaged/dam_break_3d_fluid_00200.vtu  # frame 4
head -c 5000 "$bad" > cut && mv cut "$bad"
if "$sluice" convert 'damaged/*.vtu' -o serial_damaged.sluice -q 2> serial.err; then fail "serial: a damaged frame converted"; fi
if mpi 4 'damaged/*.vtu' -o mpi_damaged.sluice -q --jobs 1 2> mpi.err; then fail "mpi: a damaged frame converted"; fi
cat mpi.err
serial_message=$(head -1 serial.err)
grep -qF "${serial_message#sluice: error: }" mpi.err || fail "the MPI error is not the serial one: $serial_message"
grep -qF "(read on rank 2 of 4)" mpi.err || fail "the MPI error does not name rank 2"
grep -qF "holds the 4 frames before it" mpi.err || fail "the MPI error does not say what the output holds"
same serial_damaged.sluice mpi_damaged.sluice

echo "--- 3. --skip-bad"
"$sluice" convert 'damaged/*.vtu' -o serial_skip.sluice -q --skip-bad 2> /dev/null
mpi 4 'damaged/*.vtu' -o mpi_skip.sluice --jobs 1 --skip-bad 2> skip.err
grep -qF "skipped 1 frame that could not be read" skip.err || fail "the skipped frame is not listed"
same serial_skip.sluice mpi_skip.sluice

echo "--- 4. rank 1 dies after the first round"
if SLUICE_MPI_FAULT=exit:1 mpirun_ -x SLUICE_MPI_FAULT -np 4 \
     "$sluice" convert --mpi "$sample/dam_break_3d.pvd" -o dead.sluice -q --jobs 1 2> dead.err; then
  fail "mpirun succeeded with a dead rank"
fi
[[ ! -e dead.sluice ]] || fail "a dead rank left a file that looks complete"
[[ -e dead.sluice.partial ]] || fail "no .partial left"
"$sluice" recover dead.sluice.partial -o recovered.sluice | tee recover.out
grep -qE "^recovered 8 frames" recover.out || fail "recover did not find the first round's 8 frames"
"$sluice" verify recovered.sluice -q
echo "all MPI conversion checks passed"
