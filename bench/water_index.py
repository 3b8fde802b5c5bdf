#!/usr/bin/python3
"""The water caustic with its water's index of refraction changed (issue 43, part 1), against a
reference that needs no photon mapping: near index 1 the water vanishes (Fresnel reflectance
~1e-9 at normal incidence, refraction bending rays by ~1e-4 rad), so the scene without its
water, which BDPT renders to 0.01% in minutes, is the limit the water's image converges to.

  bench/water_index.py OUT [--indices 1.0001] [--depth -1] [--reference-seconds 120]
      [--reference-seeds 2] [--seconds 60] [--seeds 1-3] [--algorithm mlt] [--size 128]

Writes OUT/dry/scene.xml (no water) and OUT/<index>/scene.xml, renders the dry reference with
bdpt and each index with the algorithm (lax normals, as the shared reference), and prints each
render's channel means against the reference's, in percent, over the image and in two bands
(above the water, seen through it), the light's own pixels left out, and the reference's own
standard error. Paths count their water crossings as edges, so compare at an unbounded depth
(-1): at the reference's 8 edges the water's four crossings cut paths the dry scene keeps.
About reference-seeds x reference-seconds + indices x seeds x seconds of two cores.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get('FARM_SHARED_DIR', os.path.join(ROOT, '..', 'shared'))
SCENE = os.path.join(SHARED, 'scenes', 'water-caustic')
# Rows by the image's quarters: the top quarter sees the back wall above the water, the rest the
# floor and walls through it.
BANDS = [('image', (0, 4)), ('above the water', (0, 1)), ('through it', (1, 4))]


def seed_list(text):
    first, _, last = text.partition('-')
    return list(range(int(first), int(last or first) + 1))


def variant(out, name, edit):
    folder = os.path.join(out, name)
    if os.path.exists(folder):
        shutil.rmtree(folder)
    shutil.copytree(SCENE, folder)
    path = os.path.join(folder, 'scene.xml')
    text = open(path).read()
    changed = edit(text)
    if changed == text:
        raise SystemExit(f'{name}: the edit changed nothing (has the shared scene changed?)')
    open(path, 'w').write(changed)
    return path


def without_water(text):
    return re.sub(r'\s*<shape type="obj" >\s*<string name="filename" value="models/Mesh00[01]\.obj" />'
                  r'.*?</shape>', '', text, flags=re.S)


def at_index(index):
    return lambda text: text.replace('<float name="intIOR" value="1.8" />',
                                     f'<float name="intIOR" value="{index}" />')


def render(farm, scene, algorithm, seconds, seed, depth, size, image, extra=()):
    if os.path.exists(image):
        return image  # rendered by an earlier run with the same name
    done = subprocess.run([farm, 'render', scene, '--algorithm', algorithm, '--time', str(seconds),
                           '--width', str(size), '--height', str(size), '--shading-normals', 'lax',
                           '--max-depth', str(depth), '--seed', str(seed), '--threads', '2',
                           *extra, '-o', image], capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f'{image}: {done.stderr.strip()[-400:]}')
    with open(os.path.splitext(image)[0] + '.log', 'w') as log:  # the report: Z, walks lost, ...
        log.write(done.stdout + done.stderr)
    return image


def load(path):
    return np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT), dtype=np.float64)[..., :3]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('out')
    ap.add_argument('--farm', default=os.path.join(ROOT, 'build', 'bin', 'farm'))
    ap.add_argument('--indices', default='1.0001')
    ap.add_argument('--depth', type=int, default=-1)
    ap.add_argument('--algorithm', default='mlt')
    ap.add_argument('--seconds', type=float, default=60)
    ap.add_argument('--seeds', default='1-3')
    ap.add_argument('--reference-seconds', type=float, default=120)
    ap.add_argument('--reference-seeds', type=int, default=2)
    ap.add_argument('--size', type=int, default=128)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    tag = f'depth{a.depth}-{a.size}'
    dry = variant(a.out, 'dry', without_water)
    refs = [load(render(a.farm, dry, 'bdpt', a.reference_seconds, s, a.depth, a.size,
                        os.path.join(a.out, f'dry-bdpt-{tag}-{s}.exr')))
            for s in range(1001, 1001 + a.reference_seeds)]  # none of --seeds' random numbers
    ref = sum(refs) / len(refs)
    keep = (ref < np.percentile(ref, 99.9)).all(axis=2)  # the light's own pixels left out

    def means(image, quarters):
        rows = slice(a.size * quarters[0] // 4, a.size * quarters[1] // 4)
        return image[rows][keep[rows]].mean(axis=0)

    print(f'reference: the scene without water, bdpt, {len(refs)} x {a.reference_seconds:g} s; '
          f'{a.algorithm} {a.seconds:g} s; depth {a.depth}, {a.size}x{a.size}, lax normals')
    print('index,seed,' + ','.join(f'{band} {c}' for band, _ in BANDS for c in 'RGB'))
    if len(refs) > 1:
        errors = []
        for _, rows in BANDS:
            ms = np.array([means(r, rows) for r in refs])
            errors += list(100 * ms.std(axis=0, ddof=1) / np.sqrt(len(refs)) / ms.mean(axis=0))
        print('reference standard error,,' + ','.join(f'{e:.3f}' for e in errors))
    for index in a.indices.split(','):
        scene = variant(a.out, index, at_index(index))
        for seed in seed_list(a.seeds):
            image = load(render(a.farm, scene, a.algorithm, a.seconds, seed, a.depth, a.size,
                                os.path.join(a.out, f'{index}-{a.algorithm}-{tag}-{seed}.exr')))
            deviations = []
            for _, rows in BANDS:
                deviations += list(100 * (means(image, rows) / means(ref, rows) - 1))
            print(f'{index},{seed},' + ','.join(f'{d:+.2f}' for d in deviations), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
