#!/usr/bin/python3
"""References for the corpus of tools/make_corpus.py (issue 42): each scene rendered by two
different estimators, bdpt (independent bidirectional samples) and pssmlt (a Markov chain with its
own bootstrap and normalization), each as several renders of independent seeds. The reference is
their average, weighted by the inverse of each estimator's error; it is kept only where the two
agree within their errors:

- channel means: |mean_bdpt - mean_pssmlt| over the standard error of the difference, the
  standard errors from the spread between seeds (which, unlike the spread between a render's own
  chain groups, includes the error of each chain render's normalization);
- pixels: the relative MSE between the two estimators' images over the one their seed spreads
  predict (about 1 when both are unbiased; a bias anywhere in the image raises it).

Writes CORPUS/<name>/reference.exr (64x64 unless --size), CORPUS/<name>/reference.json (the
checks, the reference's own relative MSE, that a measurement can subtract from its own, and the
seconds spent) and CORPUS/references.md (the table). Renders one scene after another, two threads
each: run it alone, timings beside a build are noise.

    tools/corpus_references.py CORPUS [--farm build/bin/farm] [--seconds 12] [--seeds 4]
                               [--size 64] [--only NAME,...] [--reuse]

At the defaults a scene takes 2 x 4 x 12 s, the corpus of 27 about 45 minutes.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

import numpy as np
import OpenImageIO as oiio

ESTIMATORS = ["bdpt", "pssmlt"]


def load(path):
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        sys.exit("cannot read %s: %s" % (path, buf.geterror()))
    return np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float64)[..., :3]


def save(path, pixels):
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], 3, oiio.FLOAT)
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec):
        sys.exit("cannot write %s: %s" % (path, oiio.geterror()))
    out.write_image(pixels.astype(np.float32))
    out.close()


def relmse(image, reference):
    """imgcmp.py's relative MSE: mean over pixels and channels of (x - r)^2 / (r^2 + 0.01)."""
    return float(np.mean((image - reference) ** 2 / (reference ** 2 + 0.01)))


def render(farm, scene, algorithm, seed, seconds, size, out_dir, reuse):
    out = os.path.join(out_dir, "%s-%d.exr" % (algorithm, seed))
    log = out[:-4] + ".log"
    if reuse and os.path.exists(out):
        return load(out)
    command = [farm, "render", scene, "--algorithm", algorithm, "--time", str(seconds),
               "--seed", str(seed), "--width", str(size), "--height", str(size), "-o", out]
    with open(log, "w") as f:
        result = subprocess.run(command, stdout=f, stderr=subprocess.STDOUT)
    if result.returncode != 0:
        sys.exit("%s failed (exit %d): see %s" % (" ".join(command), result.returncode, log))
    return load(out)


def normalization_error(log):
    """Z's relative standard error as a chain render's log states it, or None."""
    with open(log) as f:
        found = re.search(r"Z = \S+ \+- \S+ \(standard error ([0-9.]+)%", f.read())
    return float(found.group(1)) / 100 if found else None


def reference_for(farm, entry, corpus, seconds, seeds, size, reuse):
    scene = os.path.join(corpus, entry["scene"])
    scene_dir = os.path.dirname(scene)
    work = os.path.join(scene_dir, "reference-renders")
    os.makedirs(work, exist_ok=True)
    start = time.time()
    renders = {a: np.stack([render(farm, scene, a, s, seconds, size, work, reuse)
                            for s in range(1, seeds + 1)]) for a in ESTIMATORS}
    spent = time.time() - start
    previous = os.path.join(scene_dir, "reference.json")
    if reuse and os.path.exists(previous):  # the renders' time, not the reading's
        with open(previous) as f:
            spent = json.load(f).get("seconds_spent", spent)
    # Each estimator's image (the mean of its seeds) and that mean's variance per pixel.
    mean = {a: r.mean(axis=0) for a, r in renders.items()}
    var = {a: r.var(axis=0, ddof=1) / seeds for a, r in renders.items()}
    # Scalar weights (per-pixel ones would follow each pixel's noise and bias the sum).
    rough = 0.5 * (mean["bdpt"] + mean["pssmlt"])
    error = {a: float(np.mean(var[a] / (rough ** 2 + 0.01))) for a in ESTIMATORS}
    inverse = {a: 1.0 / max(error[a], 1e-30) for a in ESTIMATORS}
    weight = {a: inverse[a] / sum(inverse.values()) for a in ESTIMATORS}
    reference = sum(weight[a] * mean[a] for a in ESTIMATORS)
    reference_var = sum(weight[a] ** 2 * var[a] for a in ESTIMATORS)
    # Channel means uncapped: imgcmp.py caps pixels at the reference's 99.9th percentile, but the
    # mean of a capped value depends on the noise around the cap (the edge of a large light in
    # view: pssmlt's noisier pixels lost 0.2% of the red mean to it), and only the plain mean is
    # the same for every unbiased estimator.
    channel = {a: r.reshape(seeds, -1, 3).mean(axis=1) for a, r in renders.items()}
    channel_mean = {a: c.mean(axis=0) for a, c in channel.items()}
    channel_se = {a: c.std(axis=0, ddof=1) / np.sqrt(seeds) for a, c in channel.items()}
    # Four seeds estimate a standard error poorly; a chain render's normalization Z scales its
    # whole image, and its log states Z's standard error, a floor for that of the mean.
    for a in ESTIMATORS:
        z_errors = [normalization_error(os.path.join(work, "%s-%d.log" % (a, s)))
                    for s in range(1, seeds + 1)]
        if all(e is not None for e in z_errors):
            floor = channel_mean[a] * np.sqrt(np.mean(np.square(z_errors)) / seeds)
            channel_se[a] = np.maximum(channel_se[a], floor)
    difference = channel_mean["bdpt"] - channel_mean["pssmlt"]
    difference_se = np.sqrt(channel_se["bdpt"] ** 2 + channel_se["pssmlt"] ** 2)
    z = difference / np.maximum(difference_se, 1e-30)
    observed = relmse(mean["bdpt"], mean["pssmlt"])
    predicted = float(np.mean((var["bdpt"] + var["pssmlt"]) / (reference ** 2 + 0.01)))
    save(os.path.join(scene_dir, "reference.exr"), reference)
    result = {
        "name": entry["name"], "family": entry["family"], "half": entry["half"],
        "size": size, "seconds_each": seconds, "seeds": seeds,
        "seed_list": list(range(1, seeds + 1)), "seconds_spent": round(spent, 1),
        "weights": weight,
        "estimated_relmse": error,
        "reference_relmse": float(np.mean(reference_var / (reference ** 2 + 0.01))),
        "channel_means": {a: channel_mean[a].tolist() for a in ESTIMATORS},
        "channel_standard_errors": {a: channel_se[a].tolist() for a in ESTIMATORS},
        "channel_z": z.tolist(),
        "relmse_between": observed,
        "relmse_between_predicted": predicted,
        "relmse_ratio": observed / max(predicted, 1e-30),
    }
    # Four seeds give each standard error three degrees of freedom: a |z| of 4 or more is rare
    # by chance (about 1% per channel at that count) and a pixel ratio of 3 rarer still.
    result["agree"] = bool(np.all(np.abs(z) < 4) and result["relmse_ratio"] < 3)
    with open(os.path.join(scene_dir, "reference.json"), "w") as f:
        json.dump(result, f, indent=1)
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("corpus")
    parser.add_argument("--farm", default="build/bin/farm")
    parser.add_argument("--seconds", type=float, default=12)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--only", default="")
    parser.add_argument("--reuse", action="store_true",
                        help="take renders already in CORPUS/<name>/reference-renders as they are")
    args = parser.parse_args()
    if args.seeds < 2:
        sys.exit("--seeds must be at least 2: the checks need the spread between seeds")
    with open(os.path.join(args.corpus, "corpus.json")) as f:
        corpus = json.load(f)
    only = set(filter(None, args.only.split(",")))
    rows = []
    for entry in corpus["scenes"]:
        if only and entry["name"] not in only:
            continue
        r = reference_for(args.farm, entry, args.corpus, args.seconds, args.seeds, args.size,
                          args.reuse)
        rows.append(r)
        print("%-20s %-7s z %s ratio %.2f ref relMSE %.2e %s" % (
            r["name"], r["half"], " ".join("%+.1f" % v for v in r["channel_z"]),
            r["relmse_ratio"], r["reference_relmse"], "agree" if r["agree"] else "DISAGREE"),
            flush=True)
    with open(os.path.join(args.corpus, "references.md"), "w") as f:
        f.write("| scene | family | half | bdpt - pssmlt (z per channel) | relMSE between / "
                "predicted | reference's relMSE | agree |\n|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write("| %s | %s | %s | %s | %.2f | %.2e | %s |\n" % (
                r["name"], r["family"], r["half"], " ".join("%+.1f" % v for v in r["channel_z"]),
                r["relmse_ratio"], r["reference_relmse"], "yes" if r["agree"] else "**no**"))
    disagree = [r["name"] for r in rows if not r["agree"]]
    if disagree:
        sys.exit("the estimators disagree on: " + ", ".join(disagree))


if __name__ == "__main__":
    main()
