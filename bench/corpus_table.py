#!/usr/bin/python3
"""`--algorithm auto` against each single algorithm on the corpus of tools/make_corpus.py, against
the references of tools/corpus_references.py (issue 42, part 3): relative MSE at each of --times
(10 and 30 s by default), the mean over --seeds, one half of the corpus at a time.

Each algorithm renders once per seed for the longest time (`farm compare`; its error at a shorter
time is read off its series, at the last flush before it), auto once per seed and time (its pilot
takes a share of the budget). Every error has the reference's own relative MSE taken off: the
render's and the reference's errors are independent, so the measured relative MSE is about their
sum, and left in it would draw every ratio toward 1.

Writes OUT/<scene>/seed-<n>/ (compare reports, auto-<seconds>/), OUT/table.md and OUT/table.json.
The last column rescales each render's error to its algorithm's median samples a second over the
scene's renders in the run (relative MSE falls as 1 / samples): the machine's speed scatters by
tens of percent between renders of one sitting, and this takes that scatter out of the ratios,
leaving the pick, the pilot's share of the budget and the renders' own noise.

    bench/corpus_table.py CORPUS OUT [--half measure|tune|all] [--times 10 30] [--seeds 101 102 103]
                          [--algorithms pt,bdpt,pssmlt,mmlt,mlt] [--size 64] [--table-only] [--no-auto]

A scene takes (algorithms x longest + sum of times) x seeds seconds: at the defaults 13 scenes
and three seeds about 2.2 hours. Run it alone: timings beside a build are noise.
"""
import argparse
import csv
import json
import os
import subprocess
import sys

from corpus_common import (add_corpus_arguments, corpus_scenes, geometric_mean, reference_floor,
                           reference_path, scene_path, write_table)


def series(path):
    with open(path) as f:
        return [(float(r["elapsed_seconds"]), float(r["relmse"]))
                for r in csv.DictReader(f) if r["relmse"] not in ("", "-1")]


def at(points, t):
    before = [e for s, e in points if s <= t * 1.02]
    return before[-1] if before else None


def run(command, log):
    with open(log, "w") as f:
        if subprocess.run(command, stdout=f, stderr=subprocess.STDOUT).returncode != 0:
            print("failed: %s (see %s)" % (" ".join(command), log), file=sys.stderr)


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_corpus_arguments(parser, half="measure", seeds=[101, 102, 103])
    parser.add_argument("--times", type=float, nargs="+", default=[10, 30])
    parser.add_argument("--algorithms", default="pt,bdpt,pssmlt,mmlt,mlt")
    parser.add_argument("--auto-only", action="store_true",
                        help="render auto again, keep the algorithms' series")
    parser.add_argument("--no-auto", action="store_true", help="render the algorithms only")
    args = parser.parse_args()
    algorithms = args.algorithms.split(",")
    times = sorted(args.times)
    scenes = corpus_scenes(args)
    size = ["--width", str(args.size), "--height", str(args.size)]
    for s in scenes:
        scene, reference = scene_path(args, s), reference_path(args, s)
        if not os.path.exists(reference):
            sys.exit("no reference for %s: run tools/corpus_references.py first" % s["name"])
        for seed in args.seeds if not args.table_only else []:
            d = os.path.join(args.out, s["name"], "seed-%d" % seed)
            os.makedirs(d, exist_ok=True)
            if not args.auto_only:
                run([args.farm, "compare", scene, "--algorithms", args.algorithms, "--time",
                     "%g" % times[-1], "--seed", str(seed), "--reference", reference,
                     "--report", d] + size, os.path.join(d, "compare.log"))
            for t in times if not args.no_auto else []:
                a = os.path.join(d, "auto-%g" % t)
                run([args.farm, "render", scene, "--algorithm", "auto", "--time", "%g" % t,
                     "--seed", str(seed), "--reference", reference, "--report", a,
                     "-o", a + ".exr"] + size, a + ".log")
            print("%s seed %d done" % (s["name"], seed), flush=True)
    tabulate(args, scenes, algorithms, times)


def speed(path):
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f).get("samples_per_second") or None


def median(xs):
    xs = sorted(xs)
    return 0.5 * (xs[(len(xs) - 1) // 2] + xs[len(xs) // 2]) if xs else None


def tabulate(args, scenes, algorithms, times):
    rows = []
    for s in scenes:
        floor = reference_floor(args, s)
        # The machine's speed scatters between renders of one sitting (docs/corpus.md): each
        # algorithm's median samples a second over this scene's renders of it, to which the
        # speed-corrected errors rescale each render (relative MSE falls as 1 / samples).
        speeds = {}
        for seed in args.seeds:
            d = os.path.join(args.out, s["name"], "seed-%d" % seed)
            for a in algorithms:
                v = speed(os.path.join(d, a, "report.json"))
                if v:
                    speeds.setdefault(a, []).append(v)
            for t in times:
                auto = os.path.join(d, "auto-%g" % t, "report.json")
                if os.path.exists(auto):
                    with open(auto) as f:
                        report = json.load(f)
                    if report.get("samples_per_second"):
                        speeds.setdefault(report.get("algorithm"), []).append(
                            report["samples_per_second"])
        typical = {a: median(v) for a, v in speeds.items()}
        for t in times:
            errors = {a: [] for a in algorithms + ["auto"]}
            corrected = {a: [] for a in algorithms + ["auto"]}
            picks = []
            for seed in args.seeds:
                d = os.path.join(args.out, s["name"], "seed-%d" % seed)
                for a in algorithms:
                    p = os.path.join(d, a, "error_vs_time.csv")
                    e = at(series(p), t) if os.path.exists(p) else None
                    if e is not None:
                        errors[a].append(e - floor)
                        v = speed(os.path.join(d, a, "report.json"))
                        if v and typical.get(a):
                            corrected[a].append((e - floor) * v / typical[a])
                auto = os.path.join(d, "auto-%g" % t)
                if os.path.exists(os.path.join(auto, "report.json")):
                    with open(os.path.join(auto, "report.json")) as f:
                        report = json.load(f)
                    if report.get("relmse") is not None:
                        errors["auto"].append(report["relmse"] - floor)
                        picks.append(report.get("algorithm", "?"))
                        v, a = report.get("samples_per_second"), report.get("algorithm")
                        if v and typical.get(a):
                            corrected["auto"].append((report["relmse"] - floor) * v / typical[a])
            mean = {a: sum(e) / len(e) for a, e in errors.items() if e}
            single = {a: e for a, e in mean.items() if a != "auto"}
            best = min(single, key=single.get) if single else None
            ratio = mean["auto"] / single[best] if best and "auto" in mean else None
            cmean = {a: sum(e) / len(e) for a, e in corrected.items()
                     if e and len(e) == len(errors[a])}
            csingle = {a: e for a, e in cmean.items() if a != "auto"}
            cbest = min(csingle, key=csingle.get) if csingle else None
            cratio = cmean["auto"] / csingle[cbest] if cbest and "auto" in cmean else None
            rows.append({"scene": s["name"], "family": s["family"], "half": s["half"],
                         "seconds": t, "relmse": mean, "best": best, "auto_picks": picks,
                         "ratio": ratio, "reference_relmse": floor,
                         "speed_corrected_relmse": cmean, "speed_corrected_best": cbest,
                         "speed_corrected_ratio": cratio,
                         "samples_per_second": {a: v for a, v in speeds.items()}})
    lines = ["| scene | half | s | " + " | ".join(algorithms) + " | best | auto (picks) | "
             "auto / best | at median speed: best, auto / best |",
             "|---|---|---|" + "---|" * (len(algorithms) + 4)]
    for r in rows:
        cells = ["%.3g" % r["relmse"][a] if a in r["relmse"] else "-" for a in algorithms]
        lines.append("| %s | %s | %g | %s | %s | %s (%s) | %s | %s, %s |" % (
            r["scene"], r["half"], r["seconds"], " | ".join(cells), r["best"] or "-",
            "%.3g" % r["relmse"]["auto"] if "auto" in r["relmse"] else "-",
            ",".join(r["auto_picks"]), "%.2f" % r["ratio"] if r["ratio"] else "-",
            r["speed_corrected_best"] or "-",
            "%.2f" % r["speed_corrected_ratio"] if r["speed_corrected_ratio"] else "-"))
    lines.append("")
    for t in times:
        for key, what in (("ratio", ""), ("speed_corrected_ratio", " (at median speed)")):
            ratios = [r[key] for r in rows if r["seconds"] == t and r[key]]
            if ratios:
                lines.append("%g s%s: auto within 1.2x of the best on %d of %d scenes, worst "
                             "%.2fx, geometric mean %.2fx" % (
                                 t, what, sum(x <= 1.2 for x in ratios), len(ratios),
                                 max(ratios),
                                 geometric_mean(ratios)))
    write_table(args, "table.md", lines)
    with open(os.path.join(args.out, "table.json"), "w") as f:
        json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
