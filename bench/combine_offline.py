#!/usr/bin/python3
"""Would two algorithms' images, weighted pixel by pixel, beat the best single one at equal time?
(issue 42, part 4: "no single algorithm is best everywhere in an image").

Offline, from the renders bench/corpus_table.py leaves (OUT/<scene>/seed-<n>/<algorithm>/
image.exr, each the full --times budget): for each pair of algorithms A, B and each seed k, the
combination C = w A_k + (1 - w) B_k with w = v_B / (v_A + v_B) per pixel and channel, where v_A
is A's variance estimated from the two other seeds' images ((A_i - A_j)^2 / 2, smoothed over a
5x5 window). The weights do not depend on seed k's images, so C is unbiased wherever A and B
are. C costs two renders: at equal time its relative MSE is twice the measured one (the error of
an unbiased estimator falls as 1/time; the chains' start-up error makes this a little kind to
them). Every error has the reference's own relative MSE taken off, as in corpus_table.py.

    bench/combine_offline.py CORPUS OUT [--half measure|tune|all] [--algorithms pt,bdpt,pssmlt,mmlt]
                             [--seeds 101 102 103] [--only a,b]

Prints a table: each scene's best single algorithm and its relative MSE, and each pair's
combination as a ratio to it (under 1: the combination wins at equal time).
"""
import argparse
import itertools
import os

import numpy as np
import OpenImageIO as oiio

from corpus_common import add_corpus_arguments, corpus_scenes, reference_floor, reference_path


def read_rgb(path):
    image = oiio.ImageInput.open(path)
    pixels = np.asarray(image.read_image(format=oiio.FLOAT))[..., :3].astype(np.float64)
    image.close()
    return pixels


def relmse(x, r):
    # imgcmp.py's and common/film/error_metrics.h's definition
    return float(np.mean((x - r) ** 2 / (r ** 2 + 0.01)))


def box(v, radius=2):
    p = np.pad(v, ((radius, radius), (radius, radius), (0, 0)), mode="edge")
    out = np.zeros_like(v)
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            out += p[dy:dy + v.shape[0], dx:dx + v.shape[1]]
    return out / (2 * radius + 1) ** 2


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_corpus_arguments(parser, half="measure", seeds=[101, 102, 103], farm=False)
    parser.add_argument("--algorithms", default="pt,bdpt,pssmlt,mmlt")
    args = parser.parse_args()
    if len(args.seeds) < 3:
        parser.error("need three seeds or more: two give the weights of the third")
    algorithms = args.algorithms.split(",")
    scenes = corpus_scenes(args)
    pairs = list(itertools.combinations(algorithms, 2))
    print("| scene | half | best | its relMSE | " + " | ".join("+".join(p) for p in pairs) + " |")
    print("|---|---|---|---|" + "---|" * len(pairs))
    wins = {p: 0 for p in pairs}
    ratios = {p: [] for p in pairs}
    for s in scenes:
        paths = {(a, k): os.path.join(args.out, s["name"], "seed-%d" % k, a, "image.exr")
                 for a in algorithms for k in args.seeds}
        if not all(os.path.exists(p) for p in paths.values()):
            continue
        reference = read_rgb(reference_path(args, s))
        floor = reference_floor(args, s)
        image = {key: read_rgb(p) for key, p in paths.items()}
        single = {a: np.mean([relmse(image[a, k], reference) - floor for k in args.seeds])
                  for a in algorithms}
        best = min(single, key=single.get)
        cells = []
        for a, b in pairs:
            errors = []
            for k in args.seeds:
                others = [j for j in args.seeds if j != k]
                va = box(np.mean([(image[a, i] - image[a, j]) ** 2 / 2
                                  for i, j in itertools.combinations(others, 2)], axis=0))
                vb = box(np.mean([(image[b, i] - image[b, j]) ** 2 / 2
                                  for i, j in itertools.combinations(others, 2)], axis=0))
                w = (vb + 1e-30) / (va + vb + 2e-30)
                combined = w * image[a, k] + (1 - w) * image[b, k]
                errors.append(2 * (relmse(combined, reference) - floor))
            ratio = np.mean(errors) / single[best]
            ratios[a, b].append(ratio)
            wins[a, b] += ratio < 1
            cells.append("%.2f" % ratio)
        print("| %s | %s | %s | %.3g | %s |" % (s["name"], s["half"], best, single[best],
                                                 " | ".join(cells)))
    print()
    for p in pairs:
        if ratios[p]:
            print("%s: under the best single on %d of %d scenes, geometric mean %.2fx, best %.2fx"
                  % ("+".join(p), wins[p], len(ratios[p]),
                     float(np.exp(np.mean(np.log(ratios[p])))), min(ratios[p])))


if __name__ == "__main__":
    main()
