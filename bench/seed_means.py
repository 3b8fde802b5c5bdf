#!/usr/bin/python3
"""An algorithm's image mean over many seeds of a small render, against a reference algorithm's:
where one render's offset cannot tell a bias from noise, the mean over a hundred or more seeds
can, and its median beside it shows how skewed one render's error is (a heavy-tailed Z leaves most
renders low and a few high, unbiased on average).

  bench/seed_means.py OUT SCENE [--algorithm mlt] [--seeds 601-800] [--budget 512]
      [--reference bdpt] [--reference-seeds 501-520] [--reference-budget 256] [--size 32]
      [--glass-ball INDEX] [--farm-args "..."] [--algorithm-args=...]

Renders SCENE (or, with --glass-ball, bench/glass_ball_index.py's Cornell box with a glass ball
at that index) at SIZE x SIZE, unbounded depth, by work count (--mpp or --spp, never time, so
that the machine's speed does not enter), once per seed; prints the mean of each render's grey
mean (the light's pixels left out: those of the reference's mean image above 20 times its
median) against the reference's, in percent with its standard error, the median render's offset,
and Z's mean, median and the candidates' range from the reports. A 32x32 render of 512 mutations
a pixel takes about 0.8 s: 200 seeds are 3 minutes.
"""
import argparse
import os
import re
import subprocess

import numpy as np

from water_index import load, seed_list

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MARKOV = {'pssmlt', 'pssmlt-pt', 'mmlt', 'mlt'}


def render_seeds(a, scene, algorithm, seeds, budget, extra=()):
    """Each seed's grey image and, for the Markov chains, Z and its candidate count."""
    images, zs, counts = [], [], []
    for seed in seeds:
        image = os.path.join(a.out, f'{algorithm}-{seed}.exr')
        work = ['--mpp' if algorithm in MARKOV else '--spp', str(budget)]
        done = subprocess.run([a.farm, 'render', scene, '-o', image, '--algorithm', algorithm,
                               '--width', str(a.size), '--height', str(a.size), '--max-depth',
                               '-1', '--seed', str(seed), '--threads', '2'] + work +
                              a.farm_args.split() + list(extra), capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f'{image}: {done.stderr.strip()[-400:]}')
        images.append(load(image).mean(axis=2))
        z = re.search(r'Z = (\S+) \+- .* from (\d+) candidates', done.stdout)
        if z:
            zs.append(float(z.group(1)))
            counts.append(int(z.group(2)))
    return np.array(images), np.array(zs), counts


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('out')
    ap.add_argument('scene', nargs='?')
    ap.add_argument('--farm', default=os.path.join(ROOT, 'build', 'bin', 'farm'))
    ap.add_argument('--algorithm', default='mlt')
    ap.add_argument('--seeds', default='601-800')
    ap.add_argument('--budget', type=int, default=512, help='mutations or samples a pixel')
    ap.add_argument('--reference', default='bdpt')
    ap.add_argument('--reference-seeds', default='501-520')
    ap.add_argument('--reference-budget', type=int, default=256)
    ap.add_argument('--size', type=int, default=32)
    ap.add_argument('--glass-ball', help='the Cornell box with a glass ball at this index')
    ap.add_argument('--farm-args', default='', help='more options for every render')
    ap.add_argument('--algorithm-args', default='',
                    help="more options for the algorithm's renders only (not the reference's)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    scene = a.scene
    if a.glass_ball:
        from glass_ball_index import with_ball
        scene = with_ball(a.out, a.glass_ball)
    if not scene:
        raise SystemExit('give a SCENE or --glass-ball INDEX')

    reference, _, _ = render_seeds(a, scene, a.reference, seed_list(a.reference_seeds),
                                   a.reference_budget)
    mean_image = reference.mean(axis=0)
    keep = mean_image < 20 * np.median(mean_image)
    ref = np.array([r[keep].mean() for r in reference])
    renders, zs, counts = render_seeds(a, scene, a.algorithm, seed_list(a.seeds), a.budget,
                                       a.algorithm_args.split())
    means = np.array([r[keep].mean() for r in renders])

    def se(v):
        return v.std(ddof=1) / np.sqrt(len(v))
    off = means.mean() / ref.mean() - 1
    print(f'{a.reference}: {ref.mean():.6g} +- {100 * se(ref) / ref.mean():.2f}% '
          f'({len(ref)} seeds)')
    print(f'{a.algorithm}: {means.mean():.6g} ({len(means)} seeds): {100 * off:+.2f}% '
          f'+- {100 * np.hypot(se(means), se(ref)) / ref.mean():.2f}%, '
          f'{off * ref.mean() / np.hypot(se(means), se(ref)):+.1f} standard errors; median '
          f'render {100 * (np.median(means) / ref.mean() - 1):+.2f}%')
    if len(zs):
        print(f'Z: {zs.mean():.6g} +- {se(zs):.3g} (median {np.median(zs):.6g}) from '
              f'{min(counts)}-{max(counts)} candidates')


if __name__ == '__main__':
    main()
