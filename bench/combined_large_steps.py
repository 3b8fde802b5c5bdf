#!/usr/bin/python3
"""Kelemen's combination of the large steps with the chain (`--combine-large-steps`, issue 42,
part 4) against the chain alone, at equal time on the corpus of tools/make_corpus.py, against the
references of tools/corpus_references.py: relative MSE (the reference's own taken off, as
bench/corpus_table.py does) and the largest channel-mean deviation, per scene, algorithm and
seed, then the ratio combined / alone of the means over the seeds, and their geometric mean per
half and algorithm.

    bench/combined_large_steps.py CORPUS OUT [--half all] [--only NAME,...] [--seeds 101 102]
                                  [--algorithms pssmlt,mmlt] [--time 10] [--table-only]

A scene takes algorithms x 2 x seeds x time seconds. Run it alone: timings beside a build are
noise. Writes OUT/<scene>/<algorithm>-<mode>-<seed>/ (the render's report) and OUT/table.md.
"""
import argparse
import json
import os
import subprocess

import OpenImageIO as oiio

from corpus_common import (add_corpus_arguments, corpus_scenes, geometric_mean, reference_floor,
                           reference_path, scene_path, write_table)

MODES = {"alone": [], "combined": ["--combine-large-steps"]}


def render(args, s, algorithm, mode, seed):
    d = os.path.join(args.out, s["name"], "%s-%s-%d" % (algorithm, mode, seed))
    report = os.path.join(d, "report.json")
    if not args.table_only and not os.path.exists(report):
        os.makedirs(d, exist_ok=True)
        cmd = [args.farm, "render", scene_path(args, s), "--algorithm", algorithm,
               "--time", "%g" % args.time, "--seed", str(seed), "--reference",
               reference_path(args, s), "--report", d, "-o", d + ".exr",
               "--width", str(args.size), "--height", str(args.size)] + MODES[mode]
        with open(d + ".log", "w") as log:
            subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, check=True)
    if not os.path.exists(report):
        return None, d
    with open(report) as f:
        return json.load(f), d


def channel_means(path):
    image = oiio.ImageBuf(path).get_pixels(oiio.FLOAT)
    return image.reshape(-1, image.shape[-1])[:, :3].mean(axis=0)


def deviation(args, s, render_dir):
    """The largest relative deviation of a channel mean (plain means, as the references'
    checks take them) from the reference's."""
    ours, ref = channel_means(render_dir + ".exr"), channel_means(reference_path(args, s))
    return float(max(abs(ours / ref - 1)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_corpus_arguments(parser, half="all", seeds=[101, 102])
    parser.add_argument("--algorithms", default="pssmlt,mmlt")
    parser.add_argument("--time", type=float, default=10)
    args = parser.parse_args()
    algorithms = args.algorithms.split(",")
    lines = ["| scene | half | algorithm | alone | combined | combined / alone | "
             "largest mean deviation, alone and combined |", "|---|---|---|---|---|---|---|"]
    ratios = {}
    for s in corpus_scenes(args):
        floor = reference_floor(args, s)
        for a in algorithms:
            errors = {m: [] for m in MODES}
            devs = {m: [] for m in MODES}
            for seed in args.seeds:
                for m in MODES:
                    r, d = render(args, s, a, m, seed)
                    if r and r.get("relmse") is not None:
                        errors[m].append(r["relmse"] - floor)
                        devs[m].append(deviation(args, s, d))
            if not all(errors.values()):
                continue
            mean = {m: sum(e) / len(e) for m, e in errors.items()}
            ratio = mean["combined"] / mean["alone"] if mean["alone"] > 0 else float("nan")
            ratios.setdefault((s["half"], a), []).append(ratio)
            lines.append("| %s | %s | %s | %.3g | %.3g | %.2f | %s; %s |" % (
                s["name"], s["half"], a, mean["alone"], mean["combined"], ratio,
                ", ".join("%.1f%%" % (100 * d) for d in devs["alone"]),
                ", ".join("%.1f%%" % (100 * d) for d in devs["combined"])))
            print(lines[-1], flush=True)
    lines.append("")
    for (half, a), rs in sorted(ratios.items()):
        good = [r for r in rs if r > 0]
        geo = geometric_mean(good) if good else float("nan")
        lines.append("%s half, %s: combined / alone %.2f geometric mean over %d scenes, %d of "
                     "them below 1, range %.2f-%.2f" % (half, a, geo, len(rs),
                                                        sum(r < 1 for r in rs), min(rs), max(rs)))
    write_table(args, "table.md", lines)


if __name__ == "__main__":
    main()
