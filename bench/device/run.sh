#!/usr/bin/env bash
# Runs on the GPU machine (see bench/device/README.md): every benchmark the
# issues ask GPU-machine figures for, in one call. Results go to $OUT.
#   bash bench/device/run.sh [mpi] [io] [import] [layers] [band] [render] [stream] [split] [codec] [huge] [embed] [compare] [live] [stereo] [aniso] [xrsize] [firsthour] [streamcmp] [gpudecode] [gpuquick] [gpupair] [gpuab] [gpu100] [egl] [vtkpeer] [readpath] [importprobe] [relayprobe] [storeab] [gpusplit] [gpuplay] [gpuflight] [covered] [gpu100ab] [damf2] [gpusweep] [gpuvar] [relay] [relaytests] [relay100] [gpuplayall] [view] [viewall] [viewio] [tiersize] [tiergpu] [viewfull] [precision] [precision2] [precision3] [sendlite] [sendthreads] [sendcpu] [relaysub] [batchring] [housestream] [housestream1] [readrounds] [houseab]   (default: io render stream)
set -uo pipefail
# Folders on the GPU machine (it starts bare each session): SLUICE_SCRATCH holds
# the unpacked libraries and the files stages write; OUT what comes back.
T=${SLUICE_SCRATCH:-/tmp}
OUT=${OUT:-$T/out}
mkdir -p "$OUT" $T/s
tar -C $T/s -xJf .gpu/pack.tar.xz
export LD_LIBRARY_PATH=$T/s/lib
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
# The NVIDIA driver's Vulkan ICD where the system does not list it (NVIDIA_ICD overrides).
icd=${NVIDIA_ICD:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}
[[ -f /usr/share/vulkan/icd.d/nvidia_icd.json ]] || export VK_DRIVER_FILES=$icd
S=./.gpu/sluice
log() { printf '\n##### [%s] %s\n' "$(date +%T)" "$*" | tee -a "$OUT/summary.txt"; }
run() { log "$*"; "$@" 2>&1 | tee -a "$OUT/summary.txt"; }

secs() { local t0=$EPOCHREALTIME; "$@" >/dev/null 2>&1; awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.3f\n", b - a }'; }
# Two commands alternated 7 times (after a warm-up of each): medians side by side.
paired() { local la=$1 lb=$2 ca=$3 cb=$4 a=() b=(); eval "$ca" >/dev/null 2>&1; eval "$cb" >/dev/null 2>&1
  for i in 1 2 3 4 5 6 7; do a+=("$(secs bash -c "$ca")"); b+=("$(secs bash -c "$cb")"); done
  local ma mb; ma=$(printf '%s\n' "${a[@]}" | sort -n | sed -n 4p); mb=$(printf '%s\n' "${b[@]}" | sort -n | sed -n 4p)
  printf '%s: median %s s (%s)\n%s: median %s s (%s)\nratio %s\n' "$la" "$ma" "${a[*]}" "$lb" "$mb" "${b[*]}" \
    "$(awk -v a="$ma" -v b="$mb" 'BEGIN { printf "%.3f", a / b }')" | tee -a "$OUT/summary.txt"; }

log "machine"
{ nproc; grep -m1 "model name" /proc/cpuinfo; nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader; free -g | head -2; df -h "$T" | tail -1; } 2>&1 | tee -a "$OUT/summary.txt"

stages=${*:-io render stream}
for stage in $stages; do
  case $stage in
    mpi)
      # Issue "convert over MPI": 1..16 ranks of one thread beside the
      # threaded serial converter, 32 frames of 10M particles as .vtp
      # (bench/convert_mpi.sh; needs bench/device/pack_mpi.sh's bundle).
      tar -C $T -xJf .gpu/mpi.tar.xz
      (source bench/device/mpi_env.sh
       base=; [[ -x .gpu/sluice_base ]] && base=$(realpath .gpu/sluice_base)  # (pack.sh BASE=...: its serial converter beside)
       run env SLUICE=$S PARTICLES=${MPI_PARTICLES:-10M} FRAMES=${MPI_FRAMES:-32} RANKS="${MPI_RANKS:-1 2 4 8 16}" \
         SERIAL_ONE=${MPI_SERIAL_ONE:-0} BASE_SLUICE=$base ALT_ENV="${MPI_ALT_ENV:-}" ALT_RANKS="${MPI_ALT_RANKS:-}" WORK=$T/mpibench bash bench/convert_mpi.sh)
      cp $T/mpibench/convert_mpi.csv $T/mpibench/timeline_*.csv "$OUT/" 2>/dev/null
      ;;
    io)
      run $S bench io data/dam_break_3d/dam_break_3d.pvd --min-time 1
      [[ -d $T/s/big ]] && run $S bench io "$T/s/big/*.vtu" --min-time 1
      ;;
    render)
      $S convert data/dam_break_3d/dam_break_3d.pvd -o $T/dam.sluice -a rho -q -f
      run $S render $T/dam.sluice --frames 12 --out "$OUT/dam_gpu.png" --size 1920x1080 --stats -q
      run $S render $T/dam.sluice --frames 12 --out "$OUT/dam_gpu_rho.png" --size 1920x1080 --color-by rho -q \
        --camera "eye=2.6,-1.2,0.45;target=0.7,0,0.22;up=0,0,1;fov=45"
      run $S bench render --repeats 7 --real $T/dam.sluice --csv "$OUT/render.csv"
      ;;
    stream)
      run $S synth -n 10M --frames ${SYNTH_FRAMES:-120} -o $T/synth10m.sluice --force -q
      run $S bench stream $T/synth10m.sluice --memory 16G
      run $S play --headless --stats --seconds 10 --loop --fps 60 $T/synth10m.sluice
      run $S play --headless --seconds 10 --loop --fps 60 --policy skip $T/synth10m.sluice
      ;;
    split)  # after stream: other splits of the cores between reading and decoding
      run $S bench stream $T/synth10m.sluice --memory 16G --no-storage --read-threads 3 --threads 13
      run $S bench stream $T/synth10m.sluice --memory 16G --no-storage --read-threads 4 --threads 12
      ;;
    layers)  # the narrow band: picture, bytes, classification, frame time (issue 11)
      $S convert data/dam_break_3d/dam_break_3d.pvd -o $T/dam_layers.sluice -q -f
      run $S info $T/dam_layers.sluice
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      run $S bench layers $T/dam_layers.sluice --frames 0,6,12 --size 1280x720 --repeats 7
      run $S bench layers $T/dam_layers.sluice --frames 0,6,12 --size 2064x2208 --repeats 7
      if [[ -f .gpu/dam_fine.sluice ]]; then
        run $S info .gpu/dam_fine.sluice
        run $S bench layers .gpu/dam_fine.sluice --frames 0,4,8 --size 1280x720 --repeats 7
      fi
      run $S bench band data/dam_break_3d/dam_break_3d.pvd --frames 3 --min-time 1
      run $S bench band --synth 10000000 --no-exact --frames 1 --min-time 2
      run $S bench band --synth 100000000 --no-exact --frames 1 --min-time 2
      run $S bench render --repeats 7 --sizes 10M,100M --layers
      run $S bench render --repeats 7 --sizes 10M,100M --layers --size 2064x2208
      run $S synth -n 10M --frames 60 -o $T/synth10m_layers.sluice --force -q
      run $S info $T/synth10m_layers.sluice
      run $S bench stream $T/synth10m_layers.sluice --memory 16G --no-storage --surface
      run $S bench stream $T/synth10m_layers.sluice --memory 16G --no-storage
      rm -f $T/synth10m_layers.sluice
      run $S synth -n 100M --frames 6 -o $T/synth100m_layers.sluice --force -q
      run $S info $T/synth100m_layers.sluice
      run $S bench stream $T/synth100m_layers.sluice --memory 24G --no-storage --min-time 2 --surface
      rm -f $T/synth100m_layers.sluice
      ;;
    band)  # the GPU narrow-band classifier beside the CPU one (issue 11)
      run $S bench band --synth 1000000 --no-exact --frames 1 --min-time 1 --gpu >/dev/null  # warm-up
      [[ -n ${BAND_QUICK:-} ]] || run $S bench band data/dam_break_3d/dam_break_3d.pvd --frames 3 --min-time 1 --gpu --no-exact
      [[ -n ${BAND_QUICK:-} ]] || run $S bench band --synth 1000000 --no-exact --frames 1 --min-time 2 --gpu
      run $S bench band --synth 10000000 --no-exact --frames 1 --min-time 2 --gpu
      run $S bench band --synth 100000000 --no-exact --frames 1 --min-time 2 --gpu
      [[ -n ${BAND_QUICK:-} ]] && continue
      # Frames without layers, classified by the renderer when first drawn.
      $S convert data/dam_break_3d/dam_break_3d.pvd -o $T/dam_nolayers.sluice --no-layers -q -f
      run $S bench layers $T/dam_nolayers.sluice --gpu --frames 0,6,12 --repeats 7
      for n in 10M 100M; do
        $S synth -n $n --frames 2 --no-layers -o $T/synth_nolayers.sluice --force -q
        run $S bench layers $T/synth_nolayers.sluice --gpu --frames 1 --repeats 7
        run $S bench layers $T/synth_nolayers.sluice --gpu --frames 1 --repeats 7 --size 2064x2208
      done
      rm -f $T/synth_nolayers.sluice
      ;;
    band100)  # the renderer classifying a 100M-particle frame without layers
      $S synth -n 100M --frames 2 --no-layers -o $T/synth_nolayers.sluice --force -q
      run $S bench layers $T/synth_nolayers.sluice --gpu --frames 1 --repeats 7
      run $S bench layers $T/synth_nolayers.sluice --gpu --frames 1 --repeats 7 --size 2064x2208
      rm -f $T/synth_nolayers.sluice
      ;;
    huge)  # 100M particles per frame
      run $S synth -n 100M --frames 12 -o $T/synth100m.sluice --force -q
      run $S bench stream $T/synth100m.sluice --memory 24G --no-storage --min-time 2
      rm -f $T/synth100m.sluice
      ;;
    stereo)  # both eyes at 2 x (2064x2208): one pass against two mono passes; all particles, then the narrow band
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      run $S bench render --stereo --repeats 7 --sizes 1M,10M,100M --size 2064x2208
      run $S bench render --stereo --repeats 7 --sizes 10M,100M --size 2064x2208 --layers --with-depth
      ;;
    aniso)  # anisotropic particles: 10M every particle, both eyes at 2064x2208 with a host depth image,
            # spheres and ellipsoids, against pack.sh's BASE (today's binary) alternated; then 4K mono and the sample
      B=.gpu/sluice_base
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      for i in 1 2; do
        [[ -x $B ]] && run $B bench render --stereo --with-depth --repeats 7 --sizes 10M --size 2064x2208 --csv "$OUT/aniso_base_$i.csv"
        run $S bench render --stereo --with-depth --repeats 7 --sizes 10M --size 2064x2208 --ellipsoids --csv "$OUT/aniso_$i.csv"
      done
      [[ -n "${ANISO_QUICK:-}" ]] && continue  # (the stereo pair only)
      run $S bench render --repeats 7 --sizes 10M,100M --size 3840x2160 --ellipsoids --csv "$OUT/aniso_4k.csv"
      $S convert data/dam_break_3d/dam_break_3d.pvd -o $T/dam.sluice -a rho -q -f
      for p in spheres ellipsoids; do
        run $S render $T/dam.sluice --frames 12 --out "$OUT/dam_$p.png" --size 1920x1080 --particles $p --stats -q \
          --camera "eye=2.6,-1.2,0.45;target=0.7,0,0.22;up=0,0,1;fov=45"
      done
      ;;
    covered)  # issue 33 (headset and 4K): pack.sh's BASE (the binary before) alternated with this one, stereo
              # 2064x2208 with a host depth image, then 4K mono, the narrow band's rows, and the splat probes
              # (a .gpu/sluice_probe built with SLUICE_SPLAT_PROBE: 1 skips the depth loops, 2 the thickness loops)
      B=.gpu/sluice_base
      sizes=${COVERED_SIZES:-10M,100M}
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      for i in 1 2; do
        [[ -x $B ]] && run $B bench render --stereo --with-depth --repeats 5 --sizes $sizes --size 2064x2208 --csv "$OUT/stereo_base_$i.csv"
        run $S bench render --stereo --with-depth --repeats 5 --sizes $sizes --size 2064x2208 --csv "$OUT/stereo_$i.csv"
      done
      run $S bench render --stereo --with-depth --repeats 5 --sizes $sizes --size 2064x2208 --untiered --csv "$OUT/stereo_untiered.csv"
      # The host's depth holding the last frame's (copied out too), and the raster present pass, in this build.
      run $S bench render --stereo --with-depth --keep-depth --repeats 5 --sizes 10M --size 2064x2208 --csv "$OUT/stereo_keep_depth.csv"
      run $S bench render --stereo --with-depth --present-pass --repeats 5 --sizes 10M --size 2064x2208 --csv "$OUT/stereo_present_pass.csv"
      if [[ -x .gpu/sluice_probe ]]; then
        for p in ${COVERED_PROBES:-0 1 2}; do
          SLUICE_SPLAT_PROBE=$p run .gpu/sluice_probe bench render --stereo --with-depth --repeats 5 --sizes 10M --size 2064x2208 --csv "$OUT/probe_$p.csv"
        done
      fi
      [[ -n "${COVERED_QUICK:-}" ]] && continue
      [[ -x $B ]] && run $B bench render --repeats 5 --sizes $sizes --size 3840x2160 --csv "$OUT/mono4k_base.csv"
      run $S bench render --repeats 5 --sizes $sizes --size 3840x2160 --csv "$OUT/mono4k.csv"
      [[ -x $B ]] && run $B bench render --stereo --with-depth --layers --repeats 5 --sizes 100M --size 2064x2208 --csv "$OUT/layers_base.csv"
      run $S bench render --stereo --with-depth --layers --repeats 5 --sizes 100M --size 2064x2208 --csv "$OUT/layers.csv"
      ;;
    pack_out)  # last: every CSV in one file (the device tool brings back a few files only)
      (cd "$OUT" && tar -cJf csv.tar.xz *.csv && rm -f *.csv)
      ;;
    xrsize)  # one eye at 2064x2208: shading into the image against the present pass with a host depth image
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      run $S bench render --repeats 7 --sizes 10M,100M --size 2064x2208
      run $S bench render --repeats 7 --sizes 10M,100M --size 2064x2208 --with-depth
      run $S bench render --repeats 7 --sizes 10M --size 1920x1080 --with-depth
      ;;
    import)  # the importer against VTK's reader (same files and arrays), and what crash isolation costs
      # Solver-sized frames: the bundled PySPH sample tiled 6x (56,160 particles per file, 4 arrays).
      run $S bench io data/dam_break_3d/dam_break_3d.pvd --min-time 1 --tile 6 -t 1 --work-dir $T/imp
      log "convert of the .vtu copies: VTK's reader in worker processes (default) against --in-process"
      paired "workers" "--in-process" "$S convert '$T/imp/zlib_*.vtu' -o $T/iso_a.sluice -f -q" \
        "$S convert '$T/imp/zlib_*.vtu' -o $T/iso_b.sluice -f -q --in-process"
      paired "workers, raw" "--in-process, raw" "$S convert '$T/imp/raw_*.vtu' -o $T/iso_a.sluice -f -q" \
        "$S convert '$T/imp/raw_*.vtu' -o $T/iso_b.sluice -f -q --in-process"
      log "a longer series: the 13 copies 8 times over (104 frames), where starting the workers counts less"
      mkdir -p $T/imp/long
      for k in 1 2 3 4 5 6 7 8; do for f in $T/imp/raw_*.vtu; do cp "$f" "$T/imp/long/r${k}_$(basename "$f")"; done; done
      paired "workers, 104 frames" "--in-process, 104 frames" "$S convert '$T/imp/long/*.vtu' -o $T/iso_a.sluice -f -q" \
        "$S convert '$T/imp/long/*.vtu' -o $T/iso_b.sluice -f -q --in-process"
      log "the reliability issue's damaged files, each converted once: exit status and seconds"
      L=$T/imp/legacy_0.vtk; size=$(stat -c %s $L)
      head -c $((size / 2)) $L > $T/imp/cut.vtk
      LC_ALL=C sed 's/^POINTS 56160 /POINTS 99999999 /' $L > $T/imp/raised.vtk
      cp $L $T/imp/flipped.vtk
      for i in $(seq 200); do head -c 1 /dev/urandom | dd of=$T/imp/flipped.vtk bs=1 seek=$(( (RANDOM * 32768 + RANDOM) % size )) conv=notrunc status=none; done
      head -c $(( $(stat -c %s $T/imp/raw_0.vtu) / 3 )) $T/imp/raw_0.vtu > $T/imp/cut.vtu
      for f in cut.vtk raised.vtk flipped.vtk cut.vtu; do
        t0=$EPOCHREALTIME; $S convert $T/imp/$f -o $T/dmg.sluice -f -q > $T/dmg.txt 2>&1; rc=$?
        printf '%s: exit %s in %s s: %s\n' $f $rc "$(awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.3f", b - a }')" \
          "$(head -c 300 $T/dmg.txt | tr '\n' ' ')" | tee -a "$OUT/summary.txt"
      done
      log "the same on 1 thread"
      paired "workers -j1" "--in-process -j1" "$S convert '$T/imp/raw_*.vtu' -o $T/iso_a.sluice -f -q -j 1" \
        "$S convert '$T/imp/raw_*.vtu' -o $T/iso_b.sluice -f -q --in-process -j 1"
      ;;
    firsthour)  # convert's up-axis detection and the play/render cache, on real and synthetic solver output
      run $S synth -n 4M --frames 20 -o $T/fh.sluice --force -q
      run $S export $T/fh.sluice -o $T/fh/fluid.vtp -q -f
      run $S convert $T/fh/fluid.pvd -o $T/fh_a.sluice -f
      log "convert 4M x 20 .vtp with up-axis detection against --up y"
      paired "detection" "--up y" "$S convert $T/fh/fluid.pvd -o $T/fh_a.sluice -f -q" \
        "$S convert $T/fh/fluid.pvd -o $T/fh_b.sluice -f -q --up y"
      log "the bundled PySPH dam break (13 frames of 9,360) with detection against --up z"
      paired "detection" "--up z" "$S convert data/dam_break_3d/dam_break_3d.pvd -o $T/d_a.sluice -f -q" \
        "$S convert data/dam_break_3d/dam_break_3d.pvd -o $T/d_b.sluice -f -q --up z"
      log "play straight from the .pvd: first run converts into the cache, later runs reuse it"
      rm -rf $T/fh/.sluice-cache
      run $S play --headless --once --fps 1000 $T/fh/fluid.pvd
      paired "play from .pvd, cache hit" "play the .sluice itself" "$S play --headless --once --fps 1000 $T/fh/fluid.pvd" \
        "$S play --headless --once --fps 1000 $T/fh/.sluice-cache/fluid.sluice"
      ;;
    streamcmp)  # the streaming pipeline of this binary against BASE's (pack.sh BASE=...), alternated, page cache
      run $S synth -n 10M --frames 60 -o $T/s10.sluice --force -q
      for i in 1 2 3; do
        log "round $i: base"; ./.gpu/sluice_base bench stream $T/s10.sluice --memory 16G --no-storage --min-time 2 2>&1 |
          grep -E "page cache  |decode only" | tee -a "$OUT/summary.txt"
        log "round $i: this"; $S bench stream $T/s10.sluice --memory 16G --no-storage --min-time 2 2>&1 |
          grep -E "page cache  |decode only" | tee -a "$OUT/summary.txt"
      done
      ;;
    live)  # frames pushed from memory (render::LiveSource), not recorded and recorded
      run $S bench live --sizes 1M,10M --frames 6
      run $S bench live --sizes 1M,10M --frames 6 --record $T/live.sluice
      ;;
    compare)  # render figures of this binary against the baseline binary (BASE= in pack.sh), alternating
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      for pass in 1 2; do
        [[ -x ./.gpu/sluice_base ]] && run ./.gpu/sluice_base bench render --repeats 7 --sizes 10M,100M
        run $S bench render --repeats 7 --sizes 10M,100M
      done
      ;;
    embed)  # the embeddable renderer: render figures against the baseline binary (BASE= in pack.sh), and
            # playback through the renderer with frames in flight (upload against render time)
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      for pass in 1 2; do
        [[ -x ./.gpu/sluice_base ]] && run ./.gpu/sluice_base bench render --repeats 7 --sizes 10M,100M
        run $S bench render --repeats 7 --sizes 10M,100M
      done
      run $S synth -n 10M --frames 24 -o $T/synth10m_24.sluice --force -q
      run $S play --headless --gpu $T/synth10m_24.sluice --loop --seconds 12 --fps 1000 --display-hz 1000 \
        --window 32 --memory 48G --size 1920x1080
      run $S play --headless --gpu $T/synth10m_24.sluice --loop --seconds 12 --fps 1000 --display-hz 1000 \
        --window 32 --memory 48G --size 3840x2160
      ;;
    gpuquick)  # the GPU decoder alone and per pass, on a few frames (quick iterations on the kernel)
      [[ -x .gpu/sluice_gpu_decode_tests ]] && run ./.gpu/sluice_gpu_decode_tests --gtest_brief=1 --gtest_filter=-*Bundled*
      run $S synth -n 10M --frames 4 -o $T/q10m.sluice --force -q --gpu-decodable
      run $S bench stream --gpu $T/q10m.sluice --memory 16G
      run $S synth -n 100M --frames 2 -o $T/q100m.sluice --force -q --gpu-decodable
      run $S bench stream --gpu $T/q100m.sluice --memory 32G
      ;;
    gpupair)  # the GPU decoder of this build against BASE's (pack.sh BASE=...), same files, same run
      [[ -x .gpu/sluice_gpu_decode_tests ]] && run ./.gpu/sluice_gpu_decode_tests --gtest_brief=1 --gtest_filter=-*Bundled*
      run $S synth -n 10M --frames 8 -o $T/q10m.sluice --force -q --gpu-decodable
      run $S synth -n 100M --frames 3 -o $T/q100m.sluice --force -q --gpu-decodable
      for b in ./.gpu/sluice_base $S; do
        [[ -x $b ]] || continue
        run $b bench stream --gpu $T/q10m.sluice --memory 16G --no-storage --min-time 1
        run $b bench stream --gpu $T/q100m.sluice --memory 40G --no-storage --min-time 1
      done
      ;;
    gpuab)  # the pipeline into device memory, this build against BASE's, alternated 3 times (10M x 24 frames)
      run $S synth -n 10M --frames 24 -o $T/ab10m.sluice --force -q --gpu-decodable
      for round in $(seq ${AB_ROUNDS:-3}); do
        for b in ./.gpu/sluice_base $S; do
          [[ -x $b ]] || continue
          log "round $round: $b"
          $b bench stream --gpu $T/ab10m.sluice --memory 16G --no-storage --min-time 2 2>&1 | grep -E "GPU \(kept|CPU workers|pread|GPU decode alone" | tee -a "$OUT/summary.txt"
        done
      done
      rm -f $T/ab10m.sluice
      ;;
    gpuflight)  # two records in flight: this build against BASE's alternated twice (and .gpu/sluice_sse2 once, if there), then 10 readers (10M x 24 frames)
      run $S synth -n 10M --frames 24 -o $T/fl10m.sluice --force -q --gpu-decodable
      for b in ./.gpu/sluice_base $S ./.gpu/sluice_sse2 ./.gpu/sluice_base $S; do
        [[ -x $b ]] || continue
        log "$b"
        $b bench stream --gpu $T/fl10m.sluice --memory 16G --no-storage --min-time 2 2>&1 | grep -E "decoded by|GPU \(kept|CPU workers|pread|mapping|GPU decode alone" | tee -a "$OUT/summary.txt"
      done
      run $S bench stream --gpu $T/fl10m.sluice --memory 16G --no-storage --min-time 2 --read-threads 10 --threads 6
      rm -f $T/fl10m.sluice
      ;;
    gpusweep)  # the GPU path's split of 16 cores between reading and checking, twice over (10M x 24 frames), then 100M
      run $S synth -n 10M --frames 24 -o $T/sw10m.sluice --force -q --gpu-decodable
      for round in 1 2; do
        for rt in ${SWEEP_READERS:-8 10 12}; do
          log "round $round: $rt readers"
          $S bench stream --gpu $T/sw10m.sluice --memory 16G --no-storage --min-time 2 --read-threads $rt --threads $((16 - rt)) 2>&1 | grep -E "decoded by|GPU \(kept|mapping into" | tee -a "$OUT/summary.txt"
        done
      done
      if [[ -x ./.gpu/sluice_alt ]]; then  # a variant build to try, carried beside
        for round in 1 2; do
          log "round $round: .gpu/sluice_alt, 10 readers"
          ./.gpu/sluice_alt bench stream --gpu $T/sw10m.sluice --memory 16G --no-storage --min-time 2 --read-threads 10 --threads 6 2>&1 | grep -E "decoded by|GPU \(kept|mapping into" | tee -a "$OUT/summary.txt"
        done
      fi
      rm -f $T/sw10m.sluice
      run $S synth -n 100M --frames 12 -o $T/sw100m.sluice --force -q --gpu-decodable
      for rt in ${SWEEP100_READERS:-10}; do
        run $S bench stream --gpu $T/sw100m.sluice --memory 48G --no-storage --min-time 3 --read-threads $rt --threads $((16 - rt))
      done
      rm -f $T/sw100m.sluice
      ;;
    relay)  # the relayed row (window in device memory, filled through a ring) and ring shapes, 10M x 24 frames
      run $S synth -n 10M --frames 24 -o $T/rl10m.sluice --force -q --gpu-decodable
      run $S bench stream --gpu $T/rl10m.sluice --memory 16G --no-storage --min-time 2
      IFS=, read -ra rings <<< "${RELAY_RINGS:-8 8M,32 4M,8 16M}"  # shapes "SLOTS PIECE", comma-separated
      for shape in "${rings[@]}"; do
        read -r slots piece <<< "$shape"
        log "ring of $slots x $piece"
        $S bench stream --gpu $T/rl10m.sluice --memory 16G --no-storage --min-time 2 --ring-slots "$slots" --ring-piece "$piece" 2>&1 \
          | grep -E "relayed|GPU \(kept encoded\), mapped|measured again|pread, page cache|host -> device copy \(|at once" | tee -a "$OUT/summary.txt"
      done
      rm -f $T/rl10m.sluice
      ;;
    relaytests)  # the renderer's streamed-upload tests (relayed frames render as load_frame renders them) on this GPU
      [[ -x .gpu/sluice_render_tests ]] && run ./.gpu/sluice_render_tests --gtest_brief=1 --gtest_filter='StreamedUpload.*'
      ;;
    relay100)  # the relayed row at 100M particles a frame
      run $S synth -n 100M --frames ${RELAY100_FRAMES:-8} -o $T/rl100m.sluice --force -q --gpu-decodable
      run $S bench stream --gpu $T/rl100m.sluice --memory ${RELAY100_MEMORY:-48G} --no-storage --min-time 2
      rm -f $T/rl100m.sluice
      ;;
    gpuvar)  # variant builds (.gpu/sluice_v*, carried beside) against this one, alternated, 10M x 24 frames
      run $S synth -n 10M --frames 24 -o $T/gv10m.sluice --force -q --gpu-decodable
      for round in $(seq ${VAR_ROUNDS:-2}); do
        for b in $S ./.gpu/sluice_v*; do
          [[ -x $b ]] || continue
          log "round $round: $b"
          $b bench stream --gpu $T/gv10m.sluice --memory 16G --no-storage --min-time 2 2>&1 | grep -E "decoded by|GPU \(kept|mapping into|host -> device cop|pread, page cache|GPU decode alone|at once" | tee -a "$OUT/summary.txt"
        done
      done
      rm -f $T/gv10m.sluice
      ;;
    gpu100ab)  # 100M particles a frame through the GPU path, this build (and BASE's with AB100_BASE=1)
      run $S synth -n 100M --frames 12 -o $T/ab100m.sluice --force -q --gpu-decodable
      for b in $S ${AB100_BASE:+./.gpu/sluice_base}; do
        [[ -x $b ]] && run $b bench stream --gpu $T/ab100m.sluice --memory 48G --no-storage --min-time 3
      done
      rm -f $T/ab100m.sluice
      ;;
    damf2)  # the finer PySPH dam break with both F2 tests (.gpu/dam_every.sluice, .gpu/dam_asym.sluice, converted here)
      for f in every asym; do
        run $S info .gpu/dam_$f.sluice
        run $S bench layers .gpu/dam_$f.sluice --frames 0,5,10 --repeats 3
      done
      ;;
    importprobe)  # which host mappings the driver imports as device memory (.gpu/importprobe, a probe), one mode a process
      { uname -r; echo "memlock: $(ulimit -l)"; df -h /dev/shm | tail -1; } 2>&1 | tee -a "$OUT/summary.txt"
      run $S synth -n 10M --frames 24 -o $T/ip10m.sluice --force -q --gpu-decodable
      cat $T/ip10m.sluice > /dev/null
      whole=$(stat -c %s $T/ip10m.sluice)
      for bytes in 67108864 $whole; do
        for mode in anon shared_ro private_ro private_rw shared_rw; do run ./.gpu/importprobe $mode $T/ip10m.sluice $bytes; done
      done
      if cp $T/ip10m.sluice /dev/shm/ip10m.sluice 2>/dev/null; then
        for mode in shared_ro shared_rw; do run ./.gpu/importprobe $mode /dev/shm/ip10m.sluice $whole; done
        rm -f /dev/shm/ip10m.sluice
      fi
      ;;
    relayprobe)  # the smallest pipeline of the GPU path's bytes: page cache -> staging ring (CPU) -> device (GPU), by unit, ring and stores (.gpu/relayprobe)
      run $S synth -n 10M --frames 24 -o $T/rl10m.sluice --force -q --gpu-decodable
      cat $T/rl10m.sluice > /dev/null
      fb=$(( $(stat -c %s $T/rl10m.sluice) / 24 ))
      for shape in ${RELAY_SHAPES:-"$fb 2" "$fb 4" "$fb 12" "16777216 4" "16777216 8" "4194304 8" "4194304 16" "1048576 16" "1048576 64"}; do
        for stores in nt plain; do
          ./.gpu/relayprobe $T/rl10m.sluice $fb $shape ${RELAY_THREADS:-13} $stores ${RELAY_SECONDS:-3} 2>&1 | tee -a "$OUT/summary.txt"
        done
      done
      [[ -n ${RELAY_BENCH-1} ]] && run $S bench stream --gpu $T/rl10m.sluice --memory 16G --no-storage --min-time 2
      rm -f $T/rl10m.sluice
      ;;
    storeab)  # the pipeline's read with streaming or plain stores (.gpu/sluice_vplain reads SLUICE_PLAIN_STORES), by window (memory cap)
      run $S synth -n 10M --frames 24 -o $T/sa10m.sluice --force -q --gpu-decodable
      for mem in ${STORE_MEMS:-160M 300M 600M 16G}; do
        for plain in "" 1; do
          log "memory $mem, plain stores: ${plain:-no}"
          SLUICE_PLAIN_STORES=$plain ./.gpu/sluice_vplain bench stream --gpu $T/sa10m.sluice --memory $mem --no-storage --min-time 2 2>&1 | grep -E "GPU \(kept|at once|window" | tee -a "$OUT/summary.txt"
        done
      done
      rm -f $T/sa10m.sluice
      ;;
    readpath)  # ways to move frames from the page cache into a window of staging (.gpu/readpath, a probe)
      run $S synth -n 10M --frames 24 -o $T/rp10m.sluice --force -q --gpu-decodable
      [[ -x .gpu/readpath ]] && run ./.gpu/readpath $T/rp10m.sluice $(( $(stat -c %s $T/rp10m.sluice) / 24 )) ${RP_THREADS:-4 8 12 16}
      for rt in ${RP_READERS:-4 8}; do
        run $S bench stream --gpu $T/rp10m.sluice --memory 16G --no-storage --min-time 2 --read-threads $rt --threads $((16 - rt))
      done
      [[ -x ./.gpu/sluice_base ]] && run ./.gpu/sluice_base bench stream --gpu $T/rp10m.sluice --memory 16G --no-storage --min-time 2
      ;;
    gpusplit)  # the GPU path with the default split (8 + 8 on 16 cores) and 12 readers, 10M and 100M
      run $S synth -n 10M --frames 24 -o $T/rp10m.sluice --force -q --gpu-decodable
      run $S bench stream --gpu $T/rp10m.sluice --memory 16G --no-storage --min-time 2
      run $S bench stream --gpu $T/rp10m.sluice --memory 16G --no-storage --min-time 2 --read-threads 12 --threads 4
      rm -f $T/rp10m.sluice
      run $S synth -n 100M --frames 12 -o $T/g100m.sluice --force -q --gpu-decodable
      run $S bench stream --gpu $T/g100m.sluice --memory 48G --no-storage --min-time 3
      rm -f $T/g100m.sluice
      ;;
    gpuplay)  # playback through the GPU path as fast as it goes, 10M and 100M (issue 13, item 5)
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 10M --frames 24 -o $T/p10m.sluice --force -q --gpu-decodable
      run $S play --headless --gpu --stats $T/p10m.sluice --loop --seconds 8 --fps 1000 --display-hz 1000 --memory 16G
      rm -f $T/p10m.sluice
      run $S synth -n 100M --frames 12 -o $T/p100m.sluice --force -q --gpu-decodable
      run $S play --headless --gpu --stats $T/p100m.sluice --loop --seconds 8 --fps 1000 --display-hz 1000 --memory 48G
      ;;
    gpuplayall)  # playback streaming every particle (--layers all) through a window of 4 frames, 10M and 100M
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 10M --frames 24 -o $T/pa10m.sluice --force -q --gpu-decodable
      run $S play --headless --gpu --stats $T/pa10m.sluice --loop --seconds 8 --fps 1000 --display-hz 1000 --memory 16G --window 4 --layers all
      rm -f $T/pa10m.sluice
      run $S synth -n 100M --frames 12 -o $T/pa100m.sluice --force -q --gpu-decodable
      run $S play --headless --gpu --stats $T/pa100m.sluice --loop --seconds 8 --fps 1000 --display-hz 1000 --memory 48G --window 4 --layers all
      rm -f $T/pa100m.sluice
      ;;
    gpu100)  # 100M particles a frame through the GPU path, more frames than the window holds
      run $S synth -n 100M --frames 12 -o $T/g100m.sluice --force -q --gpu-decodable
      run $S bench stream --gpu $T/g100m.sluice --memory 48G --no-storage --min-time 3
      rm -f $T/g100m.sluice
      ;;
    egl)  # what the machine offers for OpenGL through EGL (the VTK peer's needs)
      { ls /usr/share/glvnd/egl_vendor.d /etc/glvnd/egl_vendor.d 2>&1; cat /usr/share/glvnd/egl_vendor.d/*.json 2>&1
        ls /usr/lib/x86_64-linux-gnu /usr/local/nvidia/lib64 2>/dev/null | grep -i -E 'nvidia|libEGL|libOpenGL|libGLdispatch' | sort -u; } 2>&1 | tee -a "$OUT/summary.txt"
      ;;
    vtkpeer)  # VTK's fluid mapper on this GPU (bench/vtk_peer, carried as .gpu/vtk_fluid_peer) beside sluice
      run $S bench render --sizes 1M --repeats 3 >/dev/null  # warm-up
      mkdir -p "$OUT/peer"
      run $S bench render --repeats 7 --sizes ${PEER_SIZES:-1M,10M} --vtk-peer ./.gpu/vtk_fluid_peer --vtk-max 100M --images "$OUT/peer"
      ;;
    gpudecode)  # frames decoded on the GPU (issue 13): the decoder's tests, the pipeline into device memory
      [[ -x .gpu/sluice_gpu_decode_tests ]] && run ./.gpu/sluice_gpu_decode_tests --gtest_brief=1 --gtest_filter=-*Bundled*
      run $S synth -n 10M --frames ${SYNTH_FRAMES:-120} -o $T/synth10m_gpu.sluice --force -q --gpu-decodable
      run $S bench stream --gpu $T/synth10m_gpu.sluice --memory 16G
      [[ -f $T/synth10m.sluice ]] || run $S synth -n 10M --frames ${SYNTH_FRAMES:-120} -o $T/synth10m.sluice --force -q
      run $S bench stream --gpu $T/synth10m.sluice --memory 16G
      run $S synth -n 100M --frames ${SYNTH100_FRAMES:-12} -o $T/synth100m_gpu.sluice --force -q --gpu-decodable
      run $S bench stream --gpu $T/synth100m_gpu.sluice --memory 48G
      ;;
    view)  # reading only what the view draws (issue 30): the 100M pool by view against the full read, mono and stereo
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames ${VIEW_FRAMES:-24} -o $T/v100m.sluice --force -q --gpu-decodable
      run $S info $T/v100m.sluice
      run $S bench view $T/v100m.sluice --steps ${VIEW_STEPS:-12} --memory 24G
      run $S bench view $T/v100m.sluice --steps ${VIEW_STEPS:-12} --memory 24G --stereo --size 2064x2208 --no-psnr
      rm -f $T/v100m.sluice
      ;;
    layout)  # issue 45: the 100M pool in format 2.0 (coarse to fine) by view, from storage and the page cache, mono
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      [[ -f $T/v20.sluice ]] || run $S synth -n 100M --frames ${VIEW_FRAMES:-16} -o $T/v20.sluice --force -q --gpu-decodable
      run $S info $T/v20.sluice | head -14
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --memory 24G --no-psnr
      ;;
    layout2)  # after layout: stereo and full detail on the same file
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --memory 24G --stereo --size 2064x2208 --no-psnr
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --memory 24G --lod-level 1 --no-psnr
      ;;
    layout15)  # the same pool written as format 1.5 (each cell's tiers together), read by this build
      rm -f $T/v20.sluice
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      [[ -f $T/v15.sluice ]] || run $S synth -n 100M --frames ${VIEW_FRAMES:-16} -o $T/v15.sluice --force -q --gpu-decodable --format 1.5
      run $S info $T/v15.sluice | head -14
      run $S bench view $T/v15.sluice --steps ${VIEW_STEPS:-12} --memory 24G --no-psnr
      ;;
    layoutab)  # issue 45, one call: pack.sh's BASE (a 1.5 reader) and this build on the pool written as 1.5, then the same pool rewritten as 2.0 by `sluice convert`, mono and stereo
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames ${VIEW_FRAMES:-12} -o $T/v15.sluice --force -q --gpu-decodable --format 1.5
      [[ -x .gpu/sluice_base ]] && run .gpu/sluice_base bench view $T/v15.sluice --steps ${VIEW_STEPS:-12} --memory 24G --no-psnr
      run $S bench view $T/v15.sluice --steps ${VIEW_STEPS:-12} --memory 24G --no-psnr
      log "convert (1.5 -> 2.0)"
      { TIMEFORMAT="convert: %R s wall"; time $S convert $T/v15.sluice -o $T/v20.sluice --force -q; } 2>&1 | tee -a "$OUT/summary.txt"
      rm -f $T/v15.sluice
      run $S info $T/v20.sluice | head -3
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --memory 24G --no-psnr
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --memory 24G --stereo --size 2064x2208 --no-psnr
      ;;
    layoutsteady)  # issue 45: the 2.0 pool, mono: the first frame apart from the rate after it, and the close-up's share in view
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames ${VIEW_FRAMES:-12} -o $T/v20.sluice --force -q --gpu-decodable
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --memory 24G --no-psnr
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --memory 24G --no-psnr --lod-level 1 --no-storage
      ;;
    layoutsteady2)  # the page cache alone, mono and stereo, 60 frames a segment (the 12-frame pool looped)
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames ${VIEW_FRAMES:-12} -o $T/v20.sluice --force -q --gpu-decodable
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --cache-steps ${CACHE_STEPS:-60} --memory 24G --no-psnr --no-storage
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --cache-steps ${CACHE_STEPS:-60} --memory 24G --no-psnr --no-storage --stereo --size 2064x2208
      ;;
    layoutparts)  # issue 45: where a step's time goes once playing (wait, commit, upload, render), storage and page cache, mono
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames ${VIEW_FRAMES:-12} -o $T/v20.sluice --force -q --gpu-decodable
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --cache-steps ${CACHE_STEPS:-60} --memory 24G --no-psnr
      ;;
    precision)  # issue 45: precision by distance (format 3.0) at the players' default error, with PSNR against the full read
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames ${VIEW_FRAMES:-12} -o $T/v30.sluice --force -q --gpu-decodable
      run $S info $T/v30.sluice --records 1
      run $S bench view $T/v30.sluice --steps ${VIEW_STEPS:-12} --cache-steps ${CACHE_STEPS:-60} --memory 24G
      ;;
    precision2)  # the same file at full precision (--position-error 0) and at 0.1 px (pictures only)
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames ${VIEW_FRAMES:-12} -o $T/v30.sluice --force -q --gpu-decodable
      run $S bench view $T/v30.sluice --steps ${VIEW_STEPS:-12} --cache-steps ${CACHE_STEPS:-60} --memory 24G --position-error 0 --no-psnr
      run $S bench view $T/v30.sluice --steps ${VIEW_STEPS:-12} --memory 24G --position-error 0.1 --no-storage
      ;;
    precision3)  # issue 45: pictures only (page cache), blobs read whole, at 0.25 and 0.1 px
      run $S synth -n 100M --frames ${VIEW_FRAMES:-12} -o $T/v30.sluice --force -q --gpu-decodable
      for e in 0.25 0.1; do
        run $S bench view $T/v30.sluice --steps ${VIEW_STEPS:-12} --memory 24G --position-error $e --no-storage
      done
      ;;
    sendlite)  # issue 45: sendthreads in little device time: one run of 13 read threads, one of 6
      run $S synth -n 100M --frames 6 -o $T/v6.sluice --force -q --gpu-decodable
      for t in 13 6; do
        run $S bench view $T/v6.sluice --steps 6 --cache-steps 40 --memory 24G --no-storage --no-psnr --read-threads $t
      done
      ;;
    sendthreads)  # issue 45: the relay's sends in bench view by read threads (13 default, 8, 6), page cache, alternated twice
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames 6 -o $T/v6.sluice --force -q --gpu-decodable
      for i in 1 2; do
        for t in 0 8 6; do
          a=(); [[ $t != 0 ]] && a=(--read-threads $t)
          run $S bench view $T/v6.sluice --steps 6 --cache-steps 60 --memory 24G --no-storage --no-psnr "${a[@]}"
        done
      done
      ;;
    ringmem)  # issue 45: the relay's ring in the driver's memory against imported anonymous memory (--ring-imported), alternated; then 6 read threads
      run $S synth -n 10M --frames 48 -o $T/t10m.sluice --force -q --gpu-decodable
      for i in 1 2; do
        run $S bench stream --gpu $T/t10m.sluice --no-storage --memory 16G --min-time 2
        run $S bench stream --gpu $T/t10m.sluice --no-storage --memory 16G --min-time 2 --ring-imported
      done
      run $S bench stream --gpu $T/t10m.sluice --no-storage --memory 16G --min-time 2 --read-threads 6
      ;;
    relayab)  # issue 45: a ring slot holds several of a demand's runs (one send); this build against BASE (pack.sh BASE=...), alternated
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames ${VIEW_FRAMES:-12} -o $T/v20.sluice --force -q --gpu-decodable
      for i in 1 2 3; do
        for b in ./.gpu/sluice_base $S; do
          run $b bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --cache-steps ${CACHE_STEPS:-60} --memory 24G --no-psnr
        done
      done
      ;;
    sendcpu)  # issue 45: is the relay's send slow for want of a core? bench view (page cache) under GNU time (.gpu/time, carried): context switches by read threads
      [[ -f $T/v6.sluice ]] || run $S synth -n 100M --frames 6 -o $T/v6.sluice --force -q --gpu-decodable
      for t in 13 8; do
        run ./.gpu/time -v $S bench view $T/v6.sluice --steps 6 --cache-steps 40 --memory 24G --no-storage --no-psnr --read-threads $t
      done
      ;;
    relaysub)  # issue 45: a frame's relay copies in one submission; .gpu/sluice_v1 (the build before, carried) and this build alternated twice, page cache, by view; under GNU time (.gpu/time) for context switches
      [[ -f $T/v6.sluice ]] || run $S synth -n 100M --frames 6 -o $T/v6.sluice --force -q --gpu-decodable
      for i in 1 2; do
        for b in ./.gpu/sluice_v1 $S; do
          run ./.gpu/time -f "%e s wall, %U s user, %S s system, %c involuntary and %w voluntary context switches" \
            $b bench view $T/v6.sluice --steps 6 --cache-steps 40 --memory 24G --no-storage --no-psnr
        done
      done
      ;;
    batchring)  # issue 45, after houseab (its files): a frame's relay copies in one submission with a ring of 2 x read threads + 4 slots (.gpu/sluice_vbatch, a variant build of 8d4c214, carried) against this build
      for b in ./.gpu/sluice_vbatch $S; do
        run $b bench stream --gpu $T/h10m.sluice --no-storage --memory 16G --min-time 2
        run $b bench view $T/h100m.sluice --steps 6 --cache-steps 40 --memory 24G --no-storage --no-psnr
      done
      ;;
    housestream)  # issue 46: houseab's stream and decode figures alone (its render rows were measured before), this build against BASE alternated twice
      [[ -f $T/h10m.sluice ]] || run $S synth -n 10M --frames 48 -o $T/h10m.sluice --force -q --gpu-decodable
      [[ -f $T/h100m.sluice ]] || run $S synth -n 100M --frames 6 -o $T/h100m.sluice --force -q --gpu-decodable
      for i in 1 2; do
        for b in ./.gpu/sluice_base $S; do
          run $b bench stream --gpu $T/h10m.sluice --no-storage --memory 16G --min-time 2
          run $b bench view $T/h100m.sluice --steps 6 --cache-steps 40 --memory 24G --no-storage --no-psnr
        done
      done
      ;;
    housestream1)  # issue 46 in little device time: bench stream --gpu of BASE and this build, once each, 10M x 24
      run $S synth -n 10M --frames 24 -o $T/h10m24.sluice --force -q --gpu-decodable
      for b in ./.gpu/sluice_base $S; do
        run $b bench stream --gpu $T/h10m24.sluice --no-storage --memory 16G --min-time 1
      done
      ;;
    readrounds)  # issue 45: frames read at once (bench view --read-rounds 2, the default, against 4), page cache, alternated twice, 100M x 6
      [[ -f $T/h100m.sluice ]] || run $S synth -n 100M --frames 6 -o $T/h100m.sluice --force -q --gpu-decodable
      for i in 1 2; do
        for r in 2 4; do
          run $S bench view $T/h100m.sluice --steps 6 --cache-steps 40 --memory 24G --no-storage --no-psnr --read-rounds $r
        done
      done
      ;;
    houseab)  # issue 46: render, stream and decode figures of this build against BASE (pack.sh BASE=...), alternated twice
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 10M --frames 48 -o $T/h10m.sluice --force -q --gpu-decodable
      run $S synth -n 100M --frames 6 -o $T/h100m.sluice --force -q --gpu-decodable
      for i in 1 2; do
        for b in ./.gpu/sluice_base $S; do
          run $b bench render --sizes 10M,100M --repeats 5
          run $b bench stream --gpu $T/h10m.sluice --no-storage --memory 16G --min-time 2
          run $b bench view $T/h100m.sluice --steps 6 --cache-steps 40 --memory 24G --no-storage --no-psnr
        done
      done
      ;;
    layoutq)  # pictures: the orbit by view against the full read (PSNR), format 2.0
      run $S bench view $T/v20.sluice --steps ${VIEW_STEPS:-12} --memory 24G --no-storage
      ;;
    viewfull)  # the same path at full detail (level 1): what the view leaves out when LOD keeps everything
      run $S synth -n 100M --frames ${VIEW_FRAMES:-24} -o $T/v100m.sluice --force -q --gpu-decodable
      run $S bench view $T/v100m.sluice --steps ${VIEW_STEPS:-12} --memory 24G --lod-level 1 --no-psnr
      rm -f $T/v100m.sluice
      ;;
    viewall)  # the view stages on one synthetic file: mono with PSNR, stereo, full detail
      run $S bench render --sizes 10M --repeats 3 >/dev/null  # warm-up
      run $S synth -n 100M --frames ${VIEW_FRAMES:-24} -o $T/v100m.sluice --force -q --gpu-decodable
      run $S bench view $T/v100m.sluice --steps ${VIEW_STEPS:-12} --memory 24G
      run $S bench view $T/v100m.sluice --steps ${VIEW_STEPS:-12} --memory 24G --stereo --size 2064x2208 --no-psnr
      run $S bench view $T/v100m.sluice --steps ${VIEW_STEPS:-12} --memory 24G --lod-level 1 --no-psnr
      rm -f $T/v100m.sluice
      ;;
    viewio)  # how the view's scattered reads go from storage: read threads, mapped or pread (overview and fly-in)
      run $S synth -n 100M --frames ${VIEW_FRAMES:-24} -o $T/v100m.sluice --force -q --gpu-decodable
      for args in "" "--pread" "--read-threads 32" "--read-threads 32 --pread" "--read-threads 4"; do
        run $S bench view $T/v100m.sluice --steps ${VIEW_STEPS:-12} --memory 24G --no-psnr $args
      done
      rm -f $T/v100m.sluice
      ;;
    tiersize)  # tiers against one record per chunk (--no-tiers): size, and the page-cache read of everything, alternated
      run $S synth -n 10M --frames 48 -o $T/t10m.sluice --force -q --gpu-decodable
      run $S synth -n 10M --frames 48 -o $T/f10m.sluice --force -q --gpu-decodable --no-tiers
      run $S synth -n 10M --frames 8 -o $T/t10mz.sluice --force -q
      run $S synth -n 10M --frames 8 -o $T/f10mz.sluice --force -q --no-tiers
      ls -l $T/t10m.sluice $T/f10m.sluice $T/t10mz.sluice $T/f10mz.sluice | tee -a "$OUT/summary.txt"
      for i in 1 2; do
        run $S bench stream $T/f10m.sluice --no-storage --memory 16G --min-time 2
        run $S bench stream $T/t10m.sluice --no-storage --memory 16G --min-time 2
      done
      rm -f $T/t10m.sluice $T/f10m.sluice $T/t10mz.sluice $T/f10mz.sluice
      ;;
    tiergpu)  # tiers against one record per chunk, reading everything through the GPU path, alternated
      run $S synth -n 10M --frames 48 -o $T/t10m.sluice --force -q --gpu-decodable
      run $S synth -n 10M --frames 48 -o $T/f10m.sluice --force -q --gpu-decodable --no-tiers
      for i in 1 2; do
        run $S bench stream --gpu $T/f10m.sluice --no-storage --memory 16G --min-time 1
        run $S bench stream --gpu $T/t10m.sluice --no-storage --memory 16G --min-time 1
      done
      rm -f $T/t10m.sluice $T/f10m.sluice
      ;;
    codec)  # after stream: the same sequence with zstd on every plane (--smallest)
      run $S synth -n 10M --frames ${SYNTH_FRAMES:-120} -o $T/synth10m_zstd.sluice --force --smallest -q
      run $S bench stream $T/synth10m_zstd.sluice --memory 16G --no-storage
      ;;
  esac
done
