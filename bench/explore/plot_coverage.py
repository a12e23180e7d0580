#!/usr/bin/env python3
"""Plots the coverage table of the exploration study (umbra_explore_study).

    plot_coverage.py coverage.csv coverage.png

One curve per explorer: the share of the reachable free space the map knows
as free, over simulated time, with the 95% line. Needs matplotlib (Debian:
python3-matplotlib).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

LABELS = {"umbra": "umbra", "octomap": "OctoMap"}
COLORS = {"umbra": "#1f6fb4", "octomap": "#d1495b"}


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    csv_path, png_path = sys.argv[1], sys.argv[2]
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{csv_path}: no rows")
    times = [float(r["time_s"]) for r in rows]
    names = [c[: -len("_coverage_percent")] for c in rows[0] if c.endswith("_coverage_percent")]
    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=120)
    for name in names:
        ax.plot(times, [float(r[f"{name}_coverage_percent"]) for r in rows], label=LABELS.get(name, name),
                color=COLORS.get(name), linewidth=2)
    ax.axhline(95.0, color="grey", linestyle="--", linewidth=1)
    ax.text(times[-1], 95.5, "95%", ha="right", va="bottom", color="grey")
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel("coverage of the reachable free space (%)")
    ax.set_xlim(0, times[-1])
    ax.set_ylim(0, 100)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right")
    ax.set_title("Next-best-view exploration of the procedural plant")
    fig.tight_layout()
    fig.savefig(png_path)


if __name__ == "__main__":
    main()
