#!/usr/bin/env python3
"""Draws an MPI conversion's timeline (SLUICE_MPI_TIMELINE's CSV, written
by bench/convert_mpi.sh as timeline_RANKS.csv): one row per rank, one bar
per step, so a rank that ends its round late or a write that waits shows.

    python3 bench/plot_mpi_timeline.py timeline_16.csv timeline_16.png [TITLE]
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLOURS = {
    "decide": "tab:grey",
    "read ahead": "tab:olive",
    "open input": "tab:pink",
    "start file": "tab:pink",
    "encode": "tab:blue",
    "read and encode": "tab:cyan",
    "wait": "tab:red",
    "write": "tab:orange",
    "tell rank 0": "tab:purple",
    "finish": "tab:brown",
}


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    rows = list(csv.DictReader(open(sys.argv[1])))
    if not rows:
        sys.exit(f"{sys.argv[1]}: no spans")
    ranks = sorted({int(r["rank"]) for r in rows})
    fig, ax = plt.subplots(figsize=(9, 0.35 * len(ranks) + 1.6), dpi=120)
    seen = set()
    for r in sorted(rows, key=lambda r: r["step"] == "read ahead"):  # inner bars last, over their step
        rank, step = int(r["rank"]), r["step"]
        start, end = float(r["start_s"]), float(r["end_s"])
        # "read ahead" lies inside "decide": drawn as a thinner bar over it.
        inner = step == "read ahead"
        ax.barh(rank, end - start, left=start, height=0.35 if inner else 0.8,
                color=COLOURS.get(step, "black"), label=None if step in seen else step)
        seen.add(step)
    ax.set_yticks(ranks, [str(n) for n in ranks])
    ax.invert_yaxis()
    ax.set_xlabel("seconds")
    ax.set_ylabel("rank")
    ax.set_title(sys.argv[3] if len(sys.argv) > 3 else "sluice convert --mpi, rank by rank")
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize="small")
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    fig.savefig(sys.argv[2])


if __name__ == "__main__":
    main()
