#!/usr/bin/python3
"""Writes a pixel allocation (common/film/pixel_allocation.h) from a pilot's images: two
independent renders of pt and two of bdpt of the same scene, film and time (issue 42, part 4;
docs/corpus.md, "Per-pixel estimators and sample density").

Each algorithm's relative error per pixel is estimated from the difference of its two renders,
(a - b)^2 / 2 over (m^2 + 0.01) with m the mean of all four (imgcmp.py's relative MSE, pixel by
pixel), summed over the channels and averaged over a (2r+1)^2 box. Renders of equal time give
errors at equal time: each cell of the film takes the algorithm whose estimate is the lower, and
a density that puts n_p ~ sqrt(e_p) / c_p samples in it (e_p the chosen algorithm's estimate, c_p
its cost a sample, from the renders' samples a second): the allocation that minimizes the mean of
e_p's at a fixed total cost (Lagrange; the error of pixel p falls as 1 / n_p). Estimates are
floored at --floor times their mean, so that no pixel the pilot saw as noiseless starves.

The pilot's images do not reach the job: the allocation depends on them alone, so the job's
image is unbiased whatever they say.

    tools/pixel_allocation.py OUT PT_A PT_B BDPT_A BDPT_B [--radius 2] [--floor 0.01]
                              [--only pt|bdpt] [--uniform]

PT_A ... are the pilot's EXRs; each needs its report.json beside it as farm render --report
writes it (DIR/report.json for DIR.exr, or --pt-rate/--bdpt-rate samples a second). --only
keeps one estimator everywhere (the density alone); --uniform keeps the density uniform (the
choice alone).
"""
import argparse
import json
import os
import struct

import numpy as np
import OpenImageIO as oiio

MAGIC, VERSION = 0x41584950, 1


def read_rgb(path):
    image = oiio.ImageInput.open(path)
    if image is None:
        raise SystemExit(f"cannot read {path}: {oiio.geterror()}")
    pixels = np.asarray(image.read_image(format=oiio.FLOAT))[..., :3].astype(np.float64)
    image.close()
    return pixels


def box(v, radius):
    if radius <= 0:
        return v
    p = np.pad(v, radius, mode="edge")
    out = np.zeros_like(v)
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            out += p[dy:dy + v.shape[0], dx:dx + v.shape[1]]
    return out / (2 * radius + 1) ** 2


def rate(exr, given):
    if given:
        return given
    report = os.path.join(os.path.splitext(exr)[0], "report.json")
    try:
        with open(report) as f:
            return float(json.load(f)["samples_per_second"])
    except (OSError, KeyError, ValueError) as e:
        raise SystemExit(f"no samples a second for {exr} ({report}: {e}); give --pt-rate/--bdpt-rate")


def allocation(pt, bdpt, pt_rate, bdpt_rate, radius=2, floor=0.01, only=None, uniform=False):
    """(density, bidirectional) per pixel from the pilot's pairs of images."""
    mean = (pt[0] + pt[1] + bdpt[0] + bdpt[1]) / 4
    denominator = mean ** 2 + 0.01
    errors = np.stack([box(((a - b) ** 2 / 2 / denominator).mean(axis=2), radius)
                       for a, b in (pt, bdpt)])
    cost = np.array([1 / pt_rate, 1 / bdpt_rate])
    if only == "pt":
        choice = np.zeros(errors.shape[1:], dtype=np.uint8)
    elif only == "bdpt":
        choice = np.ones(errors.shape[1:], dtype=np.uint8)
    else:
        choice = errors.argmin(axis=0).astype(np.uint8)
    e = np.take_along_axis(errors, choice[None].astype(np.int64), 0)[0]
    e = np.maximum(e, floor * max(e.mean(), 1e-30))
    density = np.ones_like(e) if uniform else np.sqrt(e) / cost[choice]
    return (density / density.mean()).astype(np.float32), choice


def cells(density, bidirectional, max_cells=16384):
    """The allocation in cells of size s (the smallest that keeps within max_cells, as
    PixelAllocation::cellSizeFor): a cell's density the mean of its pixels', its estimator the
    one most of them take."""
    height, width = density.shape
    s = 1
    while -(-width // s) * -(-height // s) > max_cells:
        s += 1
    cy, cx = -(-height // s), -(-width // s)
    d = np.zeros((cy, cx))
    b = np.zeros((cy, cx))
    for y in range(cy):
        for x in range(cx):
            d[y, x] = density[y * s:(y + 1) * s, x * s:(x + 1) * s].mean()
            b[y, x] = bidirectional[y * s:(y + 1) * s, x * s:(x + 1) * s].mean()
    return s, d.astype(np.float32), (b >= 0.5).astype(np.uint8)


def write(path, density, bidirectional):
    height, width = density.shape
    size, d, b = cells(density, bidirectional)
    with open(path, "wb") as f:
        f.write(struct.pack("<IIiii", MAGIC, VERSION, width, height, size))
        f.write(d.astype("<f4").tobytes())
        f.write(b.tobytes())


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("images", nargs=4, metavar="EXR", help="PT_A PT_B BDPT_A BDPT_B")
    parser.add_argument("--radius", type=int, default=2)
    parser.add_argument("--floor", type=float, default=0.01)
    parser.add_argument("--only", choices=["pt", "bdpt"])
    parser.add_argument("--uniform", action="store_true")
    parser.add_argument("--pt-rate", type=float, default=0)
    parser.add_argument("--bdpt-rate", type=float, default=0)
    args = parser.parse_args()
    images = [read_rgb(p) for p in args.images]
    if any(i.shape != images[0].shape for i in images):
        raise SystemExit("the pilot's images differ in size")
    density, choice = allocation(images[:2], images[2:], rate(args.images[0], args.pt_rate),
                                 rate(args.images[2], args.bdpt_rate), args.radius, args.floor,
                                 args.only, args.uniform)
    write(args.out, density, choice)
    print(f"{args.out}: {density.shape[1]}x{density.shape[0]}, bdpt in {choice.mean():.0%} of the "
          f"pixels, densities {density.min():.3g} to {density.max():.3g}")


if __name__ == "__main__":
    main()
