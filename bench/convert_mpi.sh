#!/usr/bin/env bash
# Conversion throughput over MPI ranks beside the threaded serial converter,
# on one machine, in one run (issue: `sluice convert --mpi`):
#   1. a synthetic series written as solver-sized VTK frames (`sluice synth`,
#      then `sluice export` to .vtp, one file per frame, with a .pvd);
#   2. the machine's bounds beside the figures: reading the input from the
#      page cache (cat), and the serial converter with every core;
#   3. the bound of N ranks on these cores: N one-thread serial converters
#      at once, each on its own frames/N frames, beside one of them alone
#      (INDEPENDENT=0 leaves it out; it needs frames divisible by the cores);
#   4. the serial converter with 1 thread, then `convert --mpi --jobs 1` at
#      each rank count; every output compared byte for byte with the serial
#      one.
# Prints a table, writes it as CSV ($WORK/convert_mpi.csv) for
# bench/plot_convert_mpi.py, and each MPI run's timeline (every rank's steps,
# SLUICE_MPI_TIMELINE) as $WORK/timeline_RANKS.csv for bench/plot_mpi_timeline.py.
#   SLUICE=build/apps/sluice/sluice PARTICLES=10M FRAMES=32 RANKS="1 2 4 8 16" WORK=/tmp/mpibench \
#     [CORES=16] [SERIAL_ONE=0] [MPIRUN=orterun] [BASE_SLUICE=other/sluice] \
#     [ALT_ENV="OMPI_MCA_fcoll=individual" [ALT_RANKS="16"]] bash bench/convert_mpi.sh
# ALT_ENV runs each rank count of ALT_RANKS (default: all) a second time with
# those variables set: an MPI-IO setting against the default, in the same
# run (timeline_RANKS_alt.csv).
set -euo pipefail
sluice=$(realpath "${SLUICE:-build/apps/sluice/sluice}")
particles=${PARTICLES:-1M} frames=${FRAMES:-16} ranks=${RANKS:-"1 2 4"}
cores=${CORES:-$(nproc)}
work=${WORK:-/tmp/sluice-mpi-bench}
as_root=(); [[ $(id -u) -eq 0 ]] && as_root=(--allow-run-as-root)
mkdir -p "$work" && cd "$work"

secs() { local t0=$EPOCHREALTIME; "$@" >/dev/null 2> last.err || { cat last.err >&2; return 1; }
         awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.3f", b - a }'; }

if [[ ! -f series/frame.pvd ]]; then
  echo "writing $frames frames of $particles particles as .vtp ($work/series)"
  "$sluice" synth -n "$particles" --frames "$frames" --speed -o synth.sluice -q -f
  "$sluice" export synth.sluice -o series/frame.vtp -q -f
  rm synth.sluice
fi
input_bytes=$(du -cb series/*.vtp | tail -1 | cut -f1)
echo "machine: $cores cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "input: $frames frames, $particles particles each, $(awk -v b="$input_bytes" 'BEGIN { printf "%.2f GB", b / 1e9 }') of .vtp"
cat series/*.vtp > /dev/null  # into the page cache
read_s=$(secs cat series/*.vtp)
convert=(convert series/frame.pvd -a speed -q -f)

echo "config,ranks,threads_per_rank,seconds,frames_per_s,identical" > convert_mpi.csv
row() {  # LABEL SECONDS [FRAMES, default all: the input bytes are scaled to them]
  local f=${3:-$frames}
  printf '%-28s %6s s  %7.2f frames/s  %7.1f MB/s in\n' "$1" "$2" "$(awk -v s="$2" -v f="$f" 'BEGIN { print f / s }')" \
    "$(awk -v s="$2" -v b="$input_bytes" -v f="$f" -v all="$frames" 'BEGIN { print b * f / all / s / 1e6 }')"; }
echo
row "bound: cat (page cache)" "$read_s"
serial_all=$(secs "$sluice" "${convert[@]}" --jobs "$cores" -o serial.sluice)
row "serial, $cores threads" "$serial_all"
if [[ -n "${BASE_SLUICE:-}" ]]; then  # another build's serial converter beside this one's, alternated 3 times
  for i in 1 2 3; do
    row "serial, $cores threads, base" "$(secs "$BASE_SLUICE" "${convert[@]}" --jobs "$cores" -o base.sluice)"
    row "serial, $cores threads" "$(secs "$sluice" "${convert[@]}" --jobs "$cores" -o serial.sluice)"
  done
fi
echo "serial_threads,1,$cores,$serial_all,$(awk -v s="$serial_all" -v f="$frames" 'BEGIN { print f / s }'),yes" >> convert_mpi.csv
if [[ "${SERIAL_ONE:-1}" == 1 ]]; then  # (SERIAL_ONE=0 leaves it out where time is short)
  serial_one=$(secs "$sluice" "${convert[@]}" --jobs 1 -o serial1.sluice)
  row "serial, 1 thread" "$serial_one"
  cmp -s serial.sluice serial1.sluice || echo "warning: the serial outputs at $cores and 1 threads differ"
  echo "serial_one,1,1,$serial_one,$(awk -v s="$serial_one" -v f="$frames" 'BEGIN { print f / s }'),yes" >> convert_mpi.csv
fi
# The machine's own bound for N ranks of one thread: N one-thread serial
# conversions of frames/N frames each, at once, each bound to its own core,
# with no MPI between them. What they lose against one conversion alone is
# what the cores lose when all are busy (shared caches, memory bandwidth,
# clocks), which no division of the work among ranks can win back.
independent() {  # N PER: N converters of PER frames each; prints the seconds until the last one finishes
  local n=$1 per=$2 k pids=()
  rm -rf parts; for (( k = 0; k < n; k++ )); do
    mkdir -p "parts/$k"
    ls series/*.vtp | sort -V | sed -n "$(( k * per + 1 )),$(( (k + 1) * per ))p" | xargs -I{} ln -s "$(pwd)/{}" "parts/$k/"
  done
  local t0=$EPOCHREALTIME
  for (( k = 0; k < n; k++ )); do
    taskset -c $(( k % cores )) "$sluice" convert "parts/$k" -a speed -q -f --jobs 1 -o "parts/$k.sluice" > /dev/null 2>&1 & pids+=($!)
  done
  for k in "${pids[@]}"; do wait "$k" || { echo "an independent converter failed" >&2; return 1; }; done
  awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.3f", b - a }'; rm -rf parts; }
if [[ "${INDEPENDENT:-1}" == 1 ]] && (( frames % cores == 0 )); then
  alone=$(independent 1 $(( frames / cores ))); row "bound: 1 converter alone" "$alone" $(( frames / cores ))
  many=$(independent "$cores" $(( frames / cores )))
  printf '%s  x%5.2f of 1 alone (ideal %d)\n' "$(row "bound: $cores converters at once" "$many")" \
    "$(awk -v a="$alone" -v b="$many" -v n="$cores" 'BEGIN { print a / b * n }')" "$cores"
  echo "independent,1,1,$alone,$(awk -v s="$alone" -v f="$(( frames / cores ))" 'BEGIN { print f / s }'),-" >> convert_mpi.csv
  echo "independent,$cores,1,$many,$(awk -v s="$many" -v f="$frames" 'BEGIN { print f / s }'),-" >> convert_mpi.csv
fi
one_rank=""
mpi_row() {  # RANKS CONFIG [VAR=VALUE ...]: one `convert --mpi` run with those variables set
  local n=$1 config=$2; shift 2
  local bind=core; (( n > cores )) && bind=none  # (more ranks than cores cannot each have one)
  local suffix=""; [[ $config != mpi ]] && suffix=_alt
  local t; t=$( (( $# )) && export "$@"; SLUICE_MPI_TIMELINE="$work/timeline_$n$suffix.csv" secs \
        timeout 3600 "${MPIRUN:-mpirun}" "${as_root[@]}" --oversubscribe --bind-to "$bind" -np "$n" \
        "$sluice" "${convert[@]}" --mpi --jobs 1 -o "mpi$n.sluice")
  local same=no; cmp -s serial.sluice "mpi$n.sluice" && same=yes
  [[ -z "$one_rank" ]] && one_rank=$t
  printf '%s  x%5.2f of 1 rank (ideal %2d), %4.2f of serial with %d threads, identical: %s\n' \
    "$(row "$config, $n ranks x 1 thread" "$t")" "$(awk -v a="$one_rank" -v b="$t" 'BEGIN { print a / b }')" "$n" \
    "$(awk -v a="$serial_all" -v b="$t" 'BEGIN { print a / b }')" "$cores" "$same"
  echo "$config,$n,1,$t,$(awk -v s="$t" -v f="$frames" 'BEGIN { print f / s }'),$same" >> convert_mpi.csv
  rm -f "mpi$n.sluice"; }
for n in $ranks; do
  mpi_row "$n" mpi
  # shellcheck disable=SC2086  # (ALT_ENV is a list of VAR=VALUE words)
  if [[ -n "${ALT_ENV:-}" && " ${ALT_RANKS:-$ranks} " == *" $n "* ]]; then mpi_row "$n" "mpi $ALT_ENV" $ALT_ENV; fi
done
echo; echo "csv: $work/convert_mpi.csv"
