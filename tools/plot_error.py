#!/usr/bin/env python3
"""Draws a report's chart: relative MSE against seconds, log-log, one curve per algorithm.

Usage: plot_error.py OUT_BASENAME NAME=CSV [NAME=CSV ...]

Each CSV is a farm error_vs_time.csv (elapsed_seconds,samples,rmse,relmse,estimated_relmse).
A curve shows relmse (against the reference) where the CSV has it, otherwise estimated_relmse
(from the spread between the job's chain groups), drawn dashed and labelled so. Writes
OUT_BASENAME.png and OUT_BASENAME.svg; each curve's SVG group has the id "curve-NAME".
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_curve(path):
    seconds, measured, estimated = [], [], []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            t = float(row["elapsed_seconds"])
            m = row.get("relmse", "")
            e = row.get("estimated_relmse", "")
            if m not in ("", None) and float(m) > 0:
                measured.append((t, float(m)))
            if e not in ("", None) and float(e) > 0:
                estimated.append((t, float(e)))
    return measured, estimated


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        return 2
    base = argv[1]
    fig, ax = plt.subplots(figsize=(8, 5.5))
    drawn = 0
    for spec in argv[2:]:
        name, _, path = spec.partition("=")
        measured, estimated = read_curve(path)
        points, style, label = measured, "-", name
        if not points:
            points, style, label = estimated, "--", name + " (estimated, no reference)"
        if not points:
            continue
        (line,) = ax.plot([p[0] for p in points], [p[1] for p in points], style, marker=".",
                          markersize=3, label=label)
        line.set_gid("curve-" + name)
        drawn += 1
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("seconds since the job's start")
    ax.set_ylabel("relative MSE")
    ax.grid(True, which="both", alpha=0.3)
    if drawn:
        ax.legend()
    fig.tight_layout()
    fig.savefig(base + ".png", dpi=110)
    fig.savefig(base + ".svg")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
