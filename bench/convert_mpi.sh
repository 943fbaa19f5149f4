#!/usr/bin/env bash
# Conversion throughput over MPI ranks beside the threaded serial converter,
# on one machine, in one run (issue: `sluice convert --mpi`):
#   1. a synthetic series written as solver-sized VTK frames (`sluice synth`,
#      then `sluice export` to .vtp, one file per frame, with a .pvd);
#   2. the machine's bounds beside the figures: reading the input from the
#      page cache (cat), and the serial converter with every core;
#   3. the serial converter with 1 thread, then `convert --mpi --jobs 1` at
#      each rank count; every output compared byte for byte with the serial
#      one.
# Prints a table, writes it as CSV ($WORK/convert_mpi.csv) for
# bench/plot_convert_mpi.py.
#   SLUICE=build/apps/sluice/sluice PARTICLES=10M FRAMES=32 RANKS="1 2 4 8 16" WORK=/tmp/mpibench \
#     [CORES=16] [SERIAL_ONE=0] [MPIRUN=orterun] [BASE_SLUICE=other/sluice] bash bench/convert_mpi.sh
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
row() { printf '%-28s %6s s  %7.2f frames/s  %7.1f MB/s in\n' "$1" "$2" "$(awk -v s="$2" -v f="$frames" 'BEGIN { print f / s }')" \
          "$(awk -v s="$2" -v b="$input_bytes" 'BEGIN { print b / s / 1e6 }')"; }
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
one_rank=""
for n in $ranks; do
  bind=core; (( n > cores )) && bind=none  # (more ranks than cores cannot each have one)
  t=$(secs timeout 3600 "${MPIRUN:-mpirun}" "${as_root[@]}" --oversubscribe --bind-to "$bind" -np "$n" \
        "$sluice" "${convert[@]}" --mpi --jobs 1 -o "mpi$n.sluice")
  same=no; cmp -s serial.sluice "mpi$n.sluice" && same=yes
  [[ -z "$one_rank" ]] && one_rank=$t
  printf '%s  x%5.2f of 1 rank (ideal %2d), %4.2f of serial with %d threads, identical: %s\n' \
    "$(row "mpi, $n ranks x 1 thread" "$t")" "$(awk -v a="$one_rank" -v b="$t" 'BEGIN { print a / b }')" "$n" \
    "$(awk -v a="$serial_all" -v b="$t" 'BEGIN { print a / b }')" "$cores" "$same"
  echo "mpi,$n,1,$t,$(awk -v s="$t" -v f="$frames" 'BEGIN { print f / s }'),$same" >> convert_mpi.csv
  rm -f "mpi$n.sluice"
done
echo; echo "csv: $work/convert_mpi.csv"
