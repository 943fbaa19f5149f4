#!/usr/bin/env python3
"""Plots bench/convert_mpi.sh's CSV: frames/s against ranks, beside ideal
scaling from one rank, the threaded serial converter, and the machine's
bound for all cores (that many one-thread converters at once, no MPI).
Rows may come from several runs of the script on one machine: each rank
count's fastest run and the median serial run are drawn.

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
    best = {}
    for r in rows:
        if r["config"] == "mpi":
            n = int(r["ranks"])
            best[n] = max(best.get(n, 0.0), float(r["frames_per_s"]))
    if not best:
        sys.exit(f"{sys.argv[1]}: no mpi rows")
    ranks = sorted(best)
    rate = [best[n] for n in ranks]
    one = rate[ranks.index(1)] if 1 in ranks else rate[0] / ranks[0]
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    ax.plot(ranks, [one * n for n in ranks], "--", color="grey", label="ideal (1 rank x ranks)")
    ax.plot(ranks, rate, "o-", label="convert --mpi, 1 thread per rank")
    serial = sorted((float(r["frames_per_s"]), r["threads_per_rank"]) for r in rows if r["config"] == "serial_threads")
    if serial:
        median, threads = serial[len(serial) // 2]
        ax.axhline(median, color="tab:red", linestyle=":", label=f"serial, {threads} threads")
    for r in rows:
        if r["config"] == "independent" and int(r["ranks"]) > 1:
            ax.plot([int(r["ranks"])], [float(r["frames_per_s"])], "s", color="tab:green",
                    label=f"bound: {r['ranks']} one-thread converters at once")
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
