#!/usr/bin/python3
"""Bit-identical images across a change of structure (issue 44): renders every algorithm on the
shared scenes and on tests/data/sky/every-material.pbrt (every BSDF model) at a fixed budget and
seed, small, and compares the pixels with another build's renders of the same.

  tools/same_images.py --farm OLD/farm --out /tmp/before
  tools/same_images.py --farm build/bin/farm --out /tmp/after --against /tmp/before

Prints one line per render (identical, or the largest difference) and exits 1 if any differs.
The EXR files themselves differ in their metadata (render time), so pixels are compared.
About 30 s on two cores.
"""
import argparse
import os
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get('FARM_SHARED_DIR', os.path.join(ROOT, '..', 'shared'))
SCENES = [os.path.join(SHARED, 'scenes', name, file) for name, file in [
    ('cornell-box', 'scene.xml'), ('cornell-box-pbrt', 'scene.pbrt'), ('veach-ajar', 'scene.pbrt'),
    ('veach-bidir', 'scene.xml'), ('veach-mis', 'scene.xml'), ('water-caustic', 'scene.xml')]]
SCENES.append(os.path.join(ROOT, 'tests', 'data', 'sky', 'every-material.pbrt'))
# Fixed budgets: a render's image depends on its seed and settings alone.
ALGORITHMS = [('pt', '--spp', 16), ('bdpt', '--spp', 8), ('pssmlt', '--mpp', 8),
              ('pssmlt-pt', '--mpp', 8), ('mmlt', '--mpp', 8), ('mlt', '--mpp', 8),
              ('erpt', '--spp', 2)]


def name_of(scene):
    base = os.path.basename(scene)
    stem = os.path.splitext(base)[0]
    return os.path.basename(os.path.dirname(scene)) if stem == 'scene' else stem


def pixels(path):
    return np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--farm', required=True, help='the farm binary to render with')
    ap.add_argument('--out', required=True, help='directory for the renders')
    ap.add_argument('--against', help="another build's --out to compare the pixels with")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    differ = 0
    for scene in SCENES:
        for algorithm, budget, amount in ALGORITHMS:
            image = os.path.join(a.out, f'{name_of(scene)}-{algorithm}.exr')
            done = subprocess.run([a.farm, 'render', scene, '--algorithm', algorithm, budget,
                                   str(amount), '--width', '48', '--height', '32', '--seed', '3',
                                   '--threads', '2', '-o', image], capture_output=True, text=True)
            if done.returncode != 0:
                print(f'{os.path.basename(image)}: render failed: {done.stderr.strip()[-300:]}')
                differ += 1
                continue
            if not a.against:
                print(f'{os.path.basename(image)}: rendered')
                continue
            mine, theirs = pixels(image), pixels(os.path.join(a.against, os.path.basename(image)))
            if mine.shape == theirs.shape and np.array_equal(mine, theirs):
                print(f'{os.path.basename(image)}: identical')
            else:
                differ += 1
                largest = np.abs(mine - theirs).max() if mine.shape == theirs.shape else np.inf
                print(f'{os.path.basename(image)}: DIFFERS (largest difference {largest:.3g})')
    if a.against:
        print(f'{differ} of {len(SCENES) * len(ALGORITHMS)} differ')
    return 1 if differ else 0


if __name__ == '__main__':
    sys.exit(main())
