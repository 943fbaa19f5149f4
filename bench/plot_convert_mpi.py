#!/usr/bin/env python3
"""Plots bench/convert_mpi.sh's CSV: frames/s against ranks, beside ideal
scaling from one rank and the threaded serial converter.

    python3 bench/plot_convert_mpi.py convert_mpi.csv convert_mpi.png [TITLE]
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    rows = list(csv.DictReader(open(sys.argv[1])))
    mpi = [r for r in rows if r["config"] == "mpi"]
    if not mpi:
        sys.exit(f"{sys.argv[1]}: no mpi rows")
    ranks = [int(r["ranks"]) for r in mpi]
    rate = [float(r["frames_per_s"]) for r in mpi]
    one = rate[ranks.index(1)] if 1 in ranks else rate[0] / ranks[0]
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    ax.plot(ranks, [one * n for n in ranks], "--", color="grey", label="ideal (1 rank x ranks)")
    ax.plot(ranks, rate, "o-", label="convert --mpi, 1 thread per rank")
    for r in rows:
        if r["config"] == "serial_threads":
            ax.axhline(float(r["frames_per_s"]), color="tab:red", linestyle=":",
                       label=f"serial, {r['threads_per_rank']} threads")
    ax.set_xscale("log", base=2)
    ax.set_xticks(ranks, [str(n) for n in ranks])
    ax.set_xlabel("ranks")
    ax.set_ylabel("frames/s")
    ax.set_title(sys.argv[3] if len(sys.argv) > 3 else "sluice convert --mpi")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(sys.argv[2])


if __name__ == "__main__":
    main()
