#!/usr/bin/python3
"""Equal-time race over seeds: ../shared/tools/race.py's scoring and Tungsten conversion, with each
renderer given the same seed list (Tungsten's --seed, the farm's --seed), so that a rare event's
luck is sampled on both sides and the means over seeds can be compared with their standard errors.
race.py alone runs Tungsten at its fixed default seed: every row of Tungsten's is the same render.

usage: bench/race_seeds.py --time 20 --tungsten BIN --farm BIN --algorithm mmlt [--seeds 1-8]
           [--tungsten-max-bounces 8]
           [--farm-args "--shading-normals lax --max-depth 8"] SCENE.xml:REF.exr ...
Prints one CSV row per render, then per scene and renderer the mean relative MSE over the seeds,
its standard error and the mean of the largest channel-mean deviation. Run it on an idle machine.
"""
import argparse
import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.environ.get('FARM_SHARED_DIR', os.path.join(HERE, '..', '..', 'shared'))
spec = importlib.util.spec_from_file_location('race', os.path.join(SHARED, 'tools', 'race.py'))
race = importlib.util.module_from_spec(spec)
spec.loader.exec_module(race)

# The farm's names for Tungsten's integrators (race.py's table, inverted where they share a name).
TUNGSTEN = {'pt': 'path_tracer', 'bdpt': 'bidirectional_path_tracer', 'pssmlt': 'kelemen_mlt',
            'mmlt': 'multiplexed_mlt'}


def seed_list(text):
    first, _, last = text.partition('-')
    return list(range(int(first), int(last or first) + 1))


def image_size(reference):
    spec = race.oiio.ImageInput.open(reference)
    size = spec.spec().width, spec.spec().height
    spec.close()
    return size


def tungsten_run(binary, xml, reference, algorithm, seconds, threads, seed, max_bounces):
    w, h = image_size(reference)
    with tempfile.TemporaryDirectory() as tmp:
        scene = race.tungsten_scene(xml, w, h, TUNGSTEN[algorithm], tmp)
        if max_bounces is not None:
            # race.py keeps the scene file's maxDepth; a reference rendered at another depth
            # (the water caustic's: 8 where the file says 9) needs the farm's --max-depth here too.
            description = json.load(open(scene))
            description['integrator']['max_bounces'] = max_bounces
            json.dump(description, open(scene, 'w'))
        done = subprocess.run([binary, '-t', str(threads), '--timeout', f'{int(seconds)}s',
                               '--seed', str(seed), scene], capture_output=True, text=True)
        if done.returncode != 0:
            return math.nan, math.nan
        return race.score(os.path.join(tmp, 'out.pfm'), reference)


def farm_run(binary, xml, reference, algorithm, seconds, threads, seed, extra):
    w, h = image_size(reference)
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, 'out.exr')
        done = subprocess.run([binary, 'render', xml, '--algorithm', algorithm, '--time', str(seconds),
                               '--width', str(w), '--height', str(h), '--threads', str(threads),
                               '--seed', str(seed), '-o', out] + extra.split(),
                              capture_output=True, text=True)
        if done.returncode != 0 or not os.path.exists(out):
            return math.nan, math.nan
        return race.score(out, reference)


def summary(values):
    n = len(values)
    mean = sum(values) / n
    spread = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1)) if n > 1 else math.nan
    return mean, spread / math.sqrt(n)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--time', type=float, default=20)
    ap.add_argument('--tungsten', help="Tungsten's binary (left out if not given)")
    ap.add_argument('--farm', help="the farm's binary (left out if not given)")
    ap.add_argument('--algorithm', default='mmlt', choices=sorted(TUNGSTEN))
    ap.add_argument('--seeds', default='1-8', help='a range, FIRST-LAST')
    ap.add_argument('--threads', type=int, default=2)
    ap.add_argument('--farm-args', default='', help='extra farm render options')
    ap.add_argument('--tungsten-max-bounces', type=int,
                    help="Tungsten's max_bounces (edges, as the farm's --max-depth counts them); "
                         "default: the scene file's, as race.py")
    ap.add_argument('cases', nargs='+', help='SCENE.xml:REFERENCE.exr')
    a = ap.parse_args()
    seeds = seed_list(a.seeds)
    results = {}
    print('scene,renderer,algorithm,seed,relmse,max_mean_dev', flush=True)
    for case in a.cases:
        xml, reference = case.split(':')
        name = os.path.basename(os.path.dirname(xml))
        for seed in seeds:
            runs = []
            if a.tungsten:
                runs.append(('tungsten', lambda: tungsten_run(a.tungsten, xml, reference, a.algorithm,
                                                               a.time, a.threads, seed,
                                                               a.tungsten_max_bounces)))
            if a.farm:
                runs.append(('farm', lambda: farm_run(a.farm, xml, reference, a.algorithm, a.time,
                                                      a.threads, seed, a.farm_args)))
            for renderer, run in runs:
                rel, dev = run()
                results.setdefault((name, renderer), []).append((rel, dev))
                print(f'{name},{renderer},{a.algorithm},{seed},{rel:.5g},{dev:.4f}', flush=True)
    print('\nscene,renderer,seeds,mean_relmse,standard_error,mean_max_mean_dev')
    for (name, renderer), rows in results.items():
        rels = [r for r, _ in rows if not math.isnan(r)]
        devs = [d for _, d in rows if not math.isnan(d)]
        if not rels:
            print(f'{name},{renderer},0,nan,nan,nan')
            continue
        mean, error = summary(rels)
        print(f'{name},{renderer},{len(rels)},{mean:.5g},{error:.2g},{sum(devs) / len(devs):.4f}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
