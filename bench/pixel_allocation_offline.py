#!/usr/bin/python3
"""What a pixel allocation (common/film/pixel_allocation.h) would save, predicted offline from
renders (issue 42, part 4; docs/corpus.md, "Per-pixel estimators and sample density").

OUT is what `bench/corpus_table.py CORPUS OUT --times 10 --seeds 1 2 3 --algorithms pt,bdpt
--no-auto` leaves, plus a pilot in OUT/<scene>/pilot/{pt,bdpt}-{11,12}.exr (two renders of each
algorithm, 0.5 s each, seeds 11 and 12). Each pixel's error at the full budget is the variance
of the three seeds' renders over (r^2 + 0.01); the allocation is made from the pilot alone
(tools/pixel_allocation.py's rule), and its error predicted by scaling each pixel's error by
the samples it would get against the samples it had. The prediction treats every strategy's
variance as falling with the pixel's own samples: light tracing's falls with all the
bidirectional samples of the film instead, so it is kind wherever light tracing carries a
pixel (the measured renders in docs/corpus.md fell short of it).

    bench/pixel_allocation_offline.py CORPUS OUT [--radius 2]
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
from pixel_allocation import allocation, read_rgb  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("corpus")
    parser.add_argument("out")
    parser.add_argument("--radius", type=int, default=2)
    args = parser.parse_args()
    algorithms, seeds = ["pt", "bdpt"], [1, 2, 3]
    print("| scene | best | its relMSE | the other / best | density alone | choice and density |")
    print("|---|---|---|---|---|---|")
    for scene in sorted(os.listdir(args.out)):
        d = os.path.join(args.out, scene)
        if not os.path.exists(os.path.join(d, "pilot", "bdpt-12.exr")):
            continue
        r = read_rgb(os.path.join(args.corpus, scene, "reference.exr"))
        denominator = r ** 2 + 0.01
        error, samples = {}, {}
        for a in algorithms:
            renders = np.stack([read_rgb(f"{d}/seed-{k}/{a}/image.exr") for k in seeds])
            error[a] = (renders.var(axis=0, ddof=1) / denominator).mean(axis=2)
            reports = [json.load(open(f"{d}/seed-{k}/{a}/report.json")) for k in seeds]
            samples[a] = np.mean([x["work_done"] for x in reports])
        rate = {a: samples[a] / 10.0 for a in algorithms}
        single = {a: error[a].mean() for a in algorithms}
        best = min(algorithms, key=single.get)
        pilot = {a: [read_rgb(f"{d}/pilot/{a}-{k}.exr") for k in (11, 12)] for a in algorithms}
        pixels = r.shape[0] * r.shape[1]

        def predicted(only):
            density, choice = allocation(pilot["pt"], pilot["bdpt"], rate["pt"], rate["bdpt"],
                                         args.radius, only=only)
            share = density / density.sum()
            cost = np.where(choice == 1, 1 / rate["bdpt"], 1 / rate["pt"])
            total = 10.0 / (share * cost).sum()  # samples in the budget
            had = np.where(choice == 1, samples["bdpt"], samples["pt"]) / pixels
            e = np.where(choice == 1, error["bdpt"], error["pt"])
            return (e * had / (total * share)).mean()

        other = max(single.values()) / single[best]
        print(f"| {scene} | {best} | {single[best]:.3g} | {other:.2f} | "
              f"{predicted(best) / single[best]:.2f} | {predicted(None) / single[best]:.2f} |")


if __name__ == "__main__":
    main()
