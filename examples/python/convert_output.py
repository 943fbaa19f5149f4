#!/usr/bin/env python3
"""Converts a solver's output to .sluice from Python, with a progress line.

    python3 convert_output.py 'out/fluid_*.vtu' run.sluice [--attribute rho ...]

The same conversion as `sluice convert` (spacing, ids, times and the up axis
found in the data); Ctrl-C stops it between frames, leaving run.sluice.partial
with the frames written (`sluice recover` makes it a file).
"""
import argparse
import sys
import time

import sluice


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("input", help="a file, a glob, a .pvd or a directory")
    parser.add_argument("output", help="the .sluice file to write")
    parser.add_argument("--attribute", action="append", default=None, help="point array to carry (repeat)")
    args = parser.parse_args()

    start = time.monotonic()

    def progress(p: dict[str, int]) -> None:
        rate = p["frames_done"] / max(time.monotonic() - start, 1e-9)
        end = "\n" if p["frames_done"] == p["frames"] else ""
        print(f"\rconverting {p['frames_done']}/{p['frames']} frames, {rate:.1f} frames/s, "
              f"{p['input_bytes'] / 1e6:.1f} MB in, {p['output_bytes'] / 1e6:.1f} MB out", end=end, flush=True)

    summary = sluice.convert(args.input, args.output, progress=progress, attributes=args.attribute)
    for note in summary["notes"]:
        print("note:", note)
    print(f"{args.output}: {summary['frames']} frames, {summary['particles']} particles, up {summary['up']} "
          f"({summary['up_evidence']}), {summary['seconds']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
