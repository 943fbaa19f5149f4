#!/usr/bin/env python3
"""The Python module against the C++ it wraps, on one file, in one run.

    PYTHONPATH=build/python python3 bench/python/bench_python.py FILE.sluice \
        [--sluice build/apps/sluice/sluice] [--memory 2G] [--min-time 3]

Rows (page cache: the file is read once first so every pass finds it there):
  - `sluice bench stream FILE --memory M`'s page-cache row: the prefetch
    pipeline into a consumer that does nothing (C++);
  - `for f in seq.frames(memory=M, window=frames/2, loop=True)`: the same
    pipeline timed the same way (looping, half the file in the window, one
    window of warm-up), every frame handed to Python as numpy arrays
    (float32 positions, LOD values, layers, attributes);
  - `sluice verify FILE`: each frame read and decoded in turn (C++);
  - `seq.frame(i)` for each frame in turn: read, decoded and handed over.
The frame(i) row is the best of repeated passes lasting at least --min-time.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import time

import sluice


def parse_bytes(text):
    m = re.fullmatch(r"([0-9.]+)([KMGT]?)", text.upper())
    if not m:
        raise SystemExit(f"--memory {text}: give bytes, e.g. 2G")
    return int(float(m.group(1)) * 1024 ** " KMGT".index(m.group(2) or " "))


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def cxx_stream_fps(exe, path, memory, min_time):
    out = run([exe, "bench", "stream", path, "--no-storage", "--memory", memory, "--min-time", str(min_time)])
    # The pipeline table's page-cache row: "  page cache     481.2 ..."
    for line in out.splitlines():
        m = re.match(r"\s+page cache\s+([0-9.]+)\s", line)
        if m:
            return float(m.group(1)), out
    raise SystemExit("no page-cache row in `sluice bench stream`'s output:\n" + out)


def cxx_verify_particles_per_s(exe, path):
    out = run([exe, "verify", path])
    m = re.search(r"([0-9.]+) M particles/s", out)
    if not m:
        raise SystemExit("no rate in `sluice verify`'s output:\n" + out)
    return float(m.group(1)) * 1e6


def best_rate(pass_fn, min_time):
    """Items per second of the best pass; passes repeat for at least min_time."""
    best, start = 0.0, time.perf_counter()
    while True:
        t = time.perf_counter()
        items = pass_fn()
        best = max(best, items / (time.perf_counter() - t))
        if time.perf_counter() - start >= min_time:
            return best


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file")
    p.add_argument("--sluice", default=shutil.which("sluice") or "build/apps/sluice/sluice")
    p.add_argument("--memory", default="2G", help="the pipeline's memory cap, both sides (default 2G)")
    p.add_argument("--min-time", type=float, default=3.0)
    a = p.parse_args()

    seq = sluice.open(a.file)
    frames, particles = len(seq), int(seq.counts.sum())
    with open(a.file, "rb") as f:  # into the page cache
        while f.read(1 << 24):
            pass
    memory = parse_bytes(a.memory)

    cxx_fps, cxx_out = cxx_stream_fps(a.sluice, a.file, a.memory, a.min_time)
    machine = next((line for line in cxx_out.splitlines() if line.startswith("machine:")), "machine: ?")

    # As `sluice bench stream` times its page-cache row: one looping stream
    # whose window holds half the file (so every frame comes through the
    # pipeline again), one window of warm-up, then --min-time of frames.
    stream = iter(seq.frames(memory=memory, window=max(2, frames // 2), loop=True))
    for _ in range(stream.window):
        next(stream)
    n, start = 0, time.perf_counter()
    while time.perf_counter() - start < a.min_time:
        next(stream)
        n += 1
    py_fps = n / (time.perf_counter() - start)
    del stream
    verify_pps = cxx_verify_particles_per_s(a.sluice, a.file)

    def frame_pass():
        for i in range(frames):
            seq.frame(i)
        return frames

    py_frame_fps = best_rate(frame_pass, a.min_time)
    verify_fps = verify_pps / (particles / frames)  # verify counts every chunk's particles and blobs

    print(f"{a.file}: {frames} frames, {len(seq.frame(0)) / 1e6:.2f} M particles in frame 0; memory cap {a.memory}; "
          f"{os.cpu_count()} cores")
    print(machine)
    print()
    print(f"{'what':<64} {'frames/s':>9} {'vs C++':>7}")
    print(f"{'-' * 64} {'-' * 9} {'-' * 7}")
    rows = [
        ("C++ pipeline -> null consumer (sluice bench stream, page cache)", cxx_fps, 1.0),
        ("Python: for f in seq.frames(memory=M, loop=True), numpy arrays", py_fps, py_fps / cxx_fps),
        ("C++ read + decode one frame at a time (sluice verify)", verify_fps, 1.0),
        ("Python: seq.frame(i) one frame at a time, numpy arrays", py_frame_fps, py_frame_fps / verify_fps),
    ]
    for name, fps, ratio in rows:
        print(f"{name:<64} {fps:9.1f} {ratio:6.2f}x")
    print()
    print(f"seq.frame(i) costs {verify_fps / py_frame_fps:.2f}x the C++ read + decode of a frame "
          f"(sluice verify decodes the blobs too, frame(i) every particle without them)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
