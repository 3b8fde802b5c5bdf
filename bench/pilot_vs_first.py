#!/usr/bin/python3
"""What auto's pilot is worth: on each scene of one half of the corpus, `--algorithm auto --pilot`
(a pilot of each of the plan's candidates picks, common/render/algorithm_pilot.h) against
`--algorithm auto` alone (the plan's first candidate, no pilot), at equal time, each render's
relative MSE against the reference less the reference's own (reference.json). A ratio over 1:
the pilot cost more than its picks saved.

Writes OUT/<scene>/seed-<n>/{pilot,first}/ and OUT/pilot_vs_first.md.

    bench/pilot_vs_first.py CORPUS OUT [--half tune|measure|all] [--seconds 30] [--seeds 101 102]
                            [--size 64] [--farm build/bin/farm] [--only a,b] [--table-only]
"""
import argparse
import json
import math
import os
import subprocess

from corpus_common import (add_corpus_arguments, corpus_scenes, reference_floor, reference_path,
                           scene_path, write_table)


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_corpus_arguments(parser, half="tune", seeds=[101, 102])
    parser.add_argument("--seconds", type=float, default=30)
    args = parser.parse_args()
    scenes = corpus_scenes(args)
    lines = ["| scene | plan's first | the pilot picked | first alone | auto --pilot | "
             "pilot / first |", "|---|---|---|---|---|---|"]
    ratios = []
    for s in scenes:
        scene, reference = scene_path(args, s), reference_path(args, s)
        floor = reference_floor(args, s)
        errors = {"pilot": [], "first": []}
        picks, first = [], None
        for seed in args.seeds:
            reports = {}
            for kind, extra in (("pilot", ["--pilot"]), ("first", [])):
                d = os.path.join(args.out, s["name"], "seed-%d" % seed, kind)
                if not args.table_only:
                    os.makedirs(d, exist_ok=True)
                    with open(d + ".log", "w") as log:
                        subprocess.run([args.farm, "render", scene, "--algorithm", "auto"] + extra +
                                       ["--time", "%g" % args.seconds, "--seed", str(seed),
                                        "--reference", reference, "--report", d, "-o", d + ".exr",
                                        "--width", str(args.size), "--height", str(args.size)],
                                       stdout=log, stderr=subprocess.STDOUT)
                p = os.path.join(d, "report.json")
                if os.path.exists(p):
                    with open(p) as f:
                        reports[kind] = json.load(f)
            if len(reports) < 2:
                continue
            for kind, r in reports.items():
                errors[kind].append(r["relmse"] - floor)
            picks.append(reports["pilot"]["algorithm"])
            first = reports["first"]["algorithm"]
        if not picks:
            continue
        pilot = sum(errors["pilot"]) / len(picks)
        alone = sum(errors["first"]) / len(picks)
        ratios.append(pilot / alone)
        lines.append("| %s | %s | %s | %.3g | %.3g | %.2f |" %
                     (s["name"], first, ",".join(picks), alone, pilot, pilot / alone))
        print(lines[-1], flush=True)
    if ratios:
        lines.append("")
        lines.append("geometric mean of pilot / first: %.2f over %d scenes, the pilot worse on %d" %
                     (math.exp(sum(map(math.log, ratios)) / len(ratios)), len(ratios),
                      sum(r > 1 for r in ratios)))
    write_table(args, "pilot_vs_first.md", lines)


if __name__ == "__main__":
    main()
