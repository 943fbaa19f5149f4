#!/usr/bin/env python3
"""Reads a .sluice sequence into numpy and plots per-frame quantities.

    python3 plot_quantity.py run.sluice [--out front.png] [--lod 0.25]

For each frame (streamed: read and decoded ahead on threads) it computes
the dam-break front (the largest x of the fluid, robust to spray: the 99.5%
quantile), the fluid's height above its lowest point and the mean density
when the file carries `rho`, and draws them against time with matplotlib.
With --lod only that fraction of the particles is read from disk (the same
particles every frame), enough for quantiles and means.
"""
import argparse
import sys

import matplotlib

matplotlib.use("Agg")  # headless: writes a file, needs no display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import sluice  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("file", help=".sluice file")
    parser.add_argument("--out", default="quantity.png", help="the plot (PNG)")
    parser.add_argument("--lod", type=float, default=None, help="fraction of particles read (0, 1]")
    args = parser.parse_args()

    seq = sluice.open(args.file)
    up = "xyz".index(seq.up[-1])
    along = 0 if up != 0 else 1  # the first horizontal axis
    wanted = ["rho"] if "rho" in seq.attributes else []
    times: list[float] = []
    front: list[float] = []
    height: list[float] = []
    rho: list[float] = []
    for f in seq.frames(lod_level=args.lod, attributes=wanted):
        p = f.positions
        # An input without times has None: the frame number stands in.
        t = f.time if f.time is not None else float(f.index)
        times.append(t)
        front.append(float(np.quantile(p[:, along], 0.995)))
        height.append(float(np.quantile(p[:, up], 0.995) - p[:, up].min()))
        if wanted:
            rho.append(float(f["rho"].mean()))
        print(f"frame {f.index:4d}  t={t:7.3f} {'s' if f.time is not None else '(no times)'}  {len(f):9d} particles  "
              f"front {front[-1]:.3f}")

    rows = 3 if wanted else 2
    fig, axes = plt.subplots(rows, 1, sharex=True, figsize=(6, 2.2 * rows))
    axes[0].plot(times, front, "o-")
    axes[0].set_ylabel(f"front ({'xyz'[along]}, 99.5%)")
    axes[1].plot(times, height, "o-", color="tab:orange")
    axes[1].set_ylabel(f"height ({seq.up})")
    if wanted:
        axes[2].plot(times, rho, "o-", color="tab:green")
        axes[2].set_ylabel("mean rho")
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(seq.path)
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
