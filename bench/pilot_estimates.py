#!/usr/bin/python3
"""How far the reference-free error estimate that auto's pilot ranks by (common/film/batch_means.h:
the spread between chain groups) is from the error against the reference, at a pilot's length:
each algorithm renders each scene of one half of the corpus for --seconds, with the reference,
and the table gives the estimate over the measured relative MSE (1: exact; the pilot's score is
the larger of this and the cross estimate, so an estimate far above 1 makes the pilot pass over
an algorithm that would have won).

Writes OUT/<scene>/<algorithm>-seed-<n>/ and OUT/estimates.md.

    bench/pilot_estimates.py CORPUS OUT [--half tune|measure|all] [--algorithms pt,bdpt,pssmlt]
                             [--seconds 1] [--seeds 101 102 103] [--size 64] [--farm build/bin/farm]
                             [--only a,b] [--table-only]
"""
import argparse
import json
import os
import subprocess

from corpus_common import (add_corpus_arguments, corpus_scenes, geometric_mean, reference_path,
                           scene_path, write_table)


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_corpus_arguments(parser, half="tune", seeds=[101, 102, 103])
    parser.add_argument("--algorithms", default="pt,bdpt,pssmlt")
    parser.add_argument("--seconds", type=float, default=1)
    args = parser.parse_args()
    algorithms = args.algorithms.split(",")
    scenes = corpus_scenes(args)
    lines = ["| scene | " + " | ".join(algorithms) + " |", "|---|" + "---|" * len(algorithms)]
    every = {a: [] for a in algorithms}
    for s in scenes:
        scene, reference = scene_path(args, s), reference_path(args, s)
        cells = []
        for a in algorithms:
            ratios = []
            for seed in args.seeds:
                d = os.path.join(args.out, s["name"], "%s-seed-%d" % (a, seed))
                if not args.table_only:
                    os.makedirs(d, exist_ok=True)
                    with open(d + ".log", "w") as log:
                        subprocess.run([args.farm, "render", scene, "--algorithm", a, "--time",
                                        "%g" % args.seconds, "--seed", str(seed), "--reference",
                                        reference, "--report", d, "-o", d + ".exr",
                                        "--width", str(args.size), "--height", str(args.size)],
                                       stdout=log, stderr=subprocess.STDOUT)
                p = os.path.join(d, "report.json")
                if not os.path.exists(p):
                    continue
                with open(p) as f:
                    r = json.load(f)
                if r.get("relmse") and r.get("estimated_relmse"):
                    ratios.append(r["estimated_relmse"] / r["relmse"])
            every[a] += ratios
            cells.append(" ".join("%.2g" % x for x in ratios) or "-")
        lines.append("| %s | %s |" % (s["name"], " | ".join(cells)))
        print(lines[-1], flush=True)
    lines.append("")
    for a in algorithms:
        if every[a]:
            lines.append("%s: estimate / measured, geometric mean %.2f, range %.2g-%.2g" % (
                a, geometric_mean(every[a]),
                min(every[a]), max(every[a])))
    write_table(args, "estimates.md", lines)


if __name__ == "__main__":
    main()
