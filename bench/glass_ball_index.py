#!/usr/bin/python3
"""A glass ball on the Cornell box's floor at several indices of refraction (issue 43, part 1),
against references from two independent estimators: under the box's large light both bdpt and
pt converge on every path the ball makes (its caustic, the floor through it, the light's
glints), so long renders of each, agreeing within their errors, are the reference.

  bench/glass_ball_index.py OUT [--indices 1.0001,1.1,1.33,1.5,2.4,4] [--seconds 60]
      [--seeds 1-2] [--algorithm mlt] [--reference-seconds 45] [--size 128]

Writes OUT/<index>/scene.xml (the shared Cornell box with a ball of radius 0.25 at (-0.45, 0.25,
0.5) in front of the tall box), renders each with bdpt (two seeds) and pt (one seed) for
reference-seconds each and with the algorithm for seconds at each seed, and prints, per index,
pt's channel means against bdpt's (the reference's check, with bdpt's own spread) and each
render's against bdpt's, in percent; a render's relative MSE against bdpt's mean image too. About
indices x (3 x reference-seconds + seeds x seconds) of two cores: 26 minutes at the defaults.
"""
import argparse
import os
import shutil
import sys

import numpy as np

from water_index import load, render, seed_list

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get('FARM_SHARED_DIR', os.path.join(ROOT, '..', 'shared'))
SCENE = os.path.join(SHARED, 'scenes', 'cornell-box')
BALL = ('  <bsdf type="dielectric" id="BallGlass"><float name="intIOR" value="{index}"/>'
        '<float name="extIOR" value="1"/></bsdf>\n'
        '  <shape type="sphere"><point name="center" x="-0.45" y="0.25" z="0.5"/>'
        '<float name="radius" value="0.25"/><ref id="BallGlass"/></shape>\n</scene>')


def with_ball(out, index):
    folder = os.path.join(out, index)
    if os.path.exists(folder):
        shutil.rmtree(folder)
    shutil.copytree(SCENE, folder)
    path = os.path.join(folder, 'scene.xml')
    text = open(path).read()
    if text.count('</scene>') != 1:
        raise SystemExit(f'{path}: expected one </scene> (has the shared scene changed?)')
    open(path, 'w').write(text.replace('</scene>', BALL.format(index=index)))
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('out')
    ap.add_argument('--farm', default=os.path.join(ROOT, 'build', 'bin', 'farm'))
    ap.add_argument('--indices', default='1.0001,1.1,1.33,1.5,2.4,4')
    ap.add_argument('--depth', type=int, default=-1)
    ap.add_argument('--algorithm', default='mlt')
    ap.add_argument('--seconds', type=float, default=60)
    ap.add_argument('--seeds', default='1-2')
    ap.add_argument('--reference-seconds', type=float, default=45)
    ap.add_argument('--size', type=int, default=128)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    tag = f'depth{a.depth}-{a.size}'
    print(f'reference: bdpt, 2 x {a.reference_seconds:g} s, checked by pt ({a.reference_seconds:g} s); '
          f'{a.algorithm} {a.seconds:g} s; depth {a.depth}, {a.size}x{a.size}')
    print('index,render,R %,G %,B %,relMSE')
    for index in a.indices.split(','):
        scene = with_ball(a.out, index)

        def run(algorithm, seconds, seed):
            return load(render(a.farm, scene, algorithm, seconds, seed, a.depth, a.size,
                               os.path.join(a.out, f'{index}-{algorithm}-{seconds:g}s-{tag}-{seed}.exr')))

        # Seeds of their own: a render of seed k draws the reference's seed-k random numbers
        # (bench/corpus_common.py), and pt's first samples are bdpt's camera subpaths.
        refs = [run('bdpt', a.reference_seconds, s) for s in (1001, 1002)]
        ref = sum(refs) / 2
        ref_means = ref.reshape(-1, 3).mean(axis=0)

        def row(name, image, mse=True):
            dev = 100 * (image.reshape(-1, 3).mean(axis=0) / ref_means - 1)
            rel = ((image - ref) ** 2 / (ref ** 2 + 1e-2)).mean() if mse else float('nan')
            print(f'{index},{name},' + ','.join(f'{d:+.2f}' for d in dev) + f',{rel:.3g}',
                  flush=True)

        spread = 100 * np.abs(refs[0].reshape(-1, 3).mean(axis=0) /
                              refs[1].reshape(-1, 3).mean(axis=0) - 1) / 2
        print(f'{index},bdpt standard error,' + ','.join(f'{d:.2f}' for d in spread) + ',')
        row('pt', run('pt', a.reference_seconds, 1003), mse=False)
        for seed in seed_list(a.seeds):
            row(f'{a.algorithm} seed {seed}', run(a.algorithm, a.seconds, seed))
    return 0


if __name__ == '__main__':
    sys.exit(main())
