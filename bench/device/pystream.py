#!/usr/bin/env python3
"""Frames/s of `for f in seq.frames(loop=True)` over FILE for SECONDS (bench/device/python_ab.sh)."""
import sys, time, sluice
seq = sluice.open(sys.argv[1]); frames = len(seq)
s = iter(seq.frames(memory=8<<30, window=max(2, frames // 2), loop=True))
for _ in range(s.window): next(s)
n, t = 0, time.perf_counter()
while time.perf_counter() - t < float(sys.argv[2]):
    next(s); n += 1
print(f"{n / (time.perf_counter() - t):.1f}")
