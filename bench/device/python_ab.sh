#!/bin/bash
# Python streaming on the GPU box: two builds of the module alternated on one
# 10M x 64 synthetic file, then bench/python/bench_python.py three times.
# Runs there from the checkout (device tool, carry .gpu and .gl). Needs, in .gpu/:
#   pack.tar.xz, sluice      bench/device/pack.sh
#   py.tar.xz                py/bin/python3.11, py/lib/python3.11 (Debian 12's, without test/,
#                            idlelib/, tkinter/, lib2to3/, ensurepip/), py/pkgs/numpy,
#                            py/libs/libblas.so.3 (the box has no Python 3.11)
#   mods.tar.xz              old/sluice and new/sluice (two build/python/sluice folders)
#   pystream.py, bench_python.py   (bench/device/pystream.py, bench/python/bench_python.py)
T=/tmp/w; mkdir -p $T/s $T/m; cd "$(dirname "$0")/../.."
tar -C $T/s -xJf .gpu/pack.tar.xz; tar -C $T -xJf .gpu/py.tar.xz; tar -C $T/m -xJf .gpu/mods.tar.xz
export LD_LIBRARY_PATH=$T/s/lib:$T/py/libs
PY="$T/py/bin/python3.11"; export PYTHONHOME=$T/py
nproc; grep -m1 "model name" /proc/cpuinfo
F=$T/s10m.sluice
time ./.gpu/sluice synth -n 10M --frames 64 -o $F > /dev/null 2>&1
cat $F > /dev/null
for r in 1 2 3 4; do
  for v in old new; do echo "$v run $r: $(PYTHONPATH=$T/m/$v:$T/py/pkgs $PY bench/device/pystream.py $F 5) frames/s"; done
done
for r in 1 2 3; do PYTHONPATH=$T/m/new:$T/py/pkgs $PY bench/python/bench_python.py $F --sluice ./.gpu/sluice --memory 16G --min-time 4 | tail -9; done
