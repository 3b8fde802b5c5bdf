#!/usr/bin/python3
"""Two builds of `farm` side by side on corpus scenes, one algorithm at a time, seeds alternating
build by build so that a drift in the machine's speed touches both alike: relative MSE against
the corpus reference (less the reference's own), each render's channel mean against the
reference's, and the standard error of Z the report gives. Made for the normalization pooled
from the bootstrap and the chains' large steps (common/mcmc/normalization.h) against the
bootstrap's alone (issue 42), and good for any change to a chain or to auto (`--algorithms auto`:
keeping the allocation pilot's samples, docs/corpus.md).

    bench/pooled_z_effect.py CORPUS OUT --before FARM --after FARM [--scenes a,b] [--algorithms
                             pssmlt,mmlt] [--seeds 101 102 103] [--seconds 30] [--size 64] [--table-only]

About 2 x scenes x algorithms x seeds x (seconds + 1) seconds. Run it alone.
"""
import argparse
import json
import os
import re
import subprocess

import numpy as np
import OpenImageIO as oiio

from corpus_common import reference_seeds


def read_rgb(path):
    image = oiio.ImageInput.open(path)
    pixels = np.asarray(image.read_image(format=oiio.FLOAT))[..., :3].astype(np.float64)
    image.close()
    return pixels


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("corpus")
    parser.add_argument("out")
    parser.add_argument("--before", required=True)
    parser.add_argument("--after", required=True)
    parser.add_argument("--scenes", default="light-in-glass-2,environment-2,light-in-glass-0")
    parser.add_argument("--algorithms", default="pssmlt,mmlt")
    parser.add_argument("--seeds", type=int, nargs="+", default=[101, 102, 103])
    parser.add_argument("--seconds", type=float, default=30)
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--table-only", action="store_true")
    args = parser.parse_args()
    builds = {"before": args.before, "after": args.after}
    os.makedirs(args.out, exist_ok=True)
    scenes, algorithms = args.scenes.split(","), args.algorithms.split(",")
    name = lambda s, a, k, b: os.path.join(args.out, "%s-%s-%d-%s" % (s, a, k, b))
    for s in scenes:  # a reference's own seeds share its random numbers (bench/corpus_common.py)
        shared = sorted(set(args.seeds) & reference_seeds(os.path.join(args.corpus, s,
                                                                       "reference.json")))
        if shared:
            raise SystemExit(f"{s}: seeds {shared} are the reference's own: use others")
    for s in scenes if not args.table_only else []:
        d = os.path.join(args.corpus, s)
        for a in algorithms:
            for k in args.seeds:
                for b, farm in builds.items():
                    with open(name(s, a, k, b) + ".log", "w") as log:
                        subprocess.run([farm, "render", os.path.join(d, "scene.xml"), "--algorithm",
                                        a, "--time", "%g" % args.seconds, "--seed", str(k),
                                        "--width", str(args.size), "--height", str(args.size),
                                        "--reference", os.path.join(d, "reference.exr"), "-o",
                                        name(s, a, k, b) + ".exr"], stdout=log,
                                       stderr=subprocess.STDOUT, check=True)
    print("| scene | algorithm | build | relMSE per seed | mean | channel mean off (%) | "
          "Z's standard error (%) |")
    print("|---|---|---|---|---|---|---|")
    fmt = lambda v: ", ".join("%.3g" % x for x in v)
    for s in scenes:
        d = os.path.join(args.corpus, s)
        reference = read_rgb(os.path.join(d, "reference.exr"))
        with open(os.path.join(d, "reference.json")) as f:
            floor = json.load(f)["reference_relmse"]
        for a in algorithms:
            for b in builds:
                errors, offsets, z = [], [], []
                for k in args.seeds:
                    image = read_rgb(name(s, a, k, b) + ".exr")
                    errors.append(float(np.mean((image - reference) ** 2 /
                                                (reference ** 2 + 0.01))) - floor)
                    offsets.append(100 * (image.mean() / reference.mean() - 1))
                    with open(name(s, a, k, b) + ".log") as f:
                        m = re.search(r"standard error ([0-9.e+-]+)%", f.read())
                    z.append(float(m.group(1)) if m else float("nan"))
                print("| %s | %s | %s | %s | %.3g | %s | %s |" % (
                    s, a, b, fmt(errors), np.mean(errors), fmt(offsets), fmt(z)))


if __name__ == "__main__":
    main()
