#!/usr/bin/python3
"""Seconds per render beside Tungsten (issue 45): the same Mitsuba scene, samples per pixel and
threads, with Tungsten's path tracer or bidirectional path tracer and the farm's pt or bdpt, one
after the other, wall-clock from process start to exit (loading included; the farm's report adds
its error estimate). Tungsten's scene is made by ../shared/tools/race.py's converter, as the
races make it; the farm runs with --shading-normals lax, as Tungsten shades.

  /usr/bin/python3 bench/anchor_speed.py --tungsten TUNGSTEN [--farm build/bin/farm] [--repeats 2]
"""
import argparse
import importlib.util
import json
import os
import subprocess
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get('FARM_SHARED_DIR', os.path.join(ROOT, '..', 'shared'))


def seconds(command):
    start = time.time()
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f'{command[0]} failed: {done.stderr.strip()[-300:]}')
    return time.time() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--tungsten', required=True)
    ap.add_argument('--farm', default=os.path.join(ROOT, 'build', 'bin', 'farm'))
    ap.add_argument('--repeats', type=int, default=2)
    ap.add_argument('--threads', default='2')
    a = ap.parse_args()
    spec = importlib.util.spec_from_file_location('race', os.path.join(SHARED, 'tools', 'race.py'))
    race = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(race)
    print('scene,algorithm,spp,tungsten_s,farm_s,tungsten_over_farm')
    for scene in ['cornell-box', 'veach-bidir']:
        xml = os.path.join(SHARED, 'scenes', scene, 'scene.xml')
        for algorithm, spp in [('pt', 64), ('bdpt', 16)]:
            tmp = tempfile.mkdtemp()
            js = race.tungsten_scene(xml, 256, 256, race.TUNGSTEN_INTEGRATORS[algorithm], tmp)
            d = json.load(open(js))
            d['renderer'].update(spp=spp, spp_step=spp)
            json.dump(d, open(js, 'w'))
            for _ in range(a.repeats):
                t = seconds([a.tungsten, '-t', a.threads, js])
                f = seconds([a.farm, 'render', xml, '--algorithm', algorithm, '--spp', str(spp),
                             '--width', '256', '--height', '256', '--threads', a.threads,
                             '--shading-normals', 'lax', '-o', os.path.join(tmp, 'farm.exr')])
                print(f'{scene},{algorithm},{spp},{t:.2f},{f:.2f},{t / f:.2f}', flush=True)


if __name__ == '__main__':
    main()
