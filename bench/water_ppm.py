#!/usr/bin/python3
"""The water caustic at other indices of refraction against photon-mapping references whose bias
is measured (issue 43, part 1).

  bench/water_ppm.py OUT --tungsten BIN [--indices 1.1,1.33,1.5,1.8,2.4,4] [--passes 64]
      [--ppm-seeds 3] [--photons 1000000] [--radius 0.05] [--size 128] [--seconds 30,60,120]
      [--seeds 1-3] [--algorithm mlt] [--bootstrap-candidates N] [--reference-only]
      [--dry-seconds 120]

For each index, OUT/scenes/<index>/scene.xml is the shared water caustic with its water's index
changed (bench/water_index.py's variant); renders go to OUT/<index>/ and are kept across runs.
Tungsten (../shared/tools/anchors/) renders it, converted by ../shared/tools/mitsuba2tungsten.py,
with its progressive photon mapper: PPM_SEEDS renders of P passes, each pass PHOTONS photons and
one camera sample a pixel, the gather radius shrinking as r_i^2 = r_0^2 prod_k (k + alpha) /
(k + 1), alpha 0.3, so about i^-0.7. The reference is their mean.

Photon mapping's bias is the blur of that radius: for a smooth image it falls as the mean of
r_i^2 over the passes, about P^-0.7. A render of P/4 passes at the first seed (the same first
passes) gives it: B(P/4) - B(P) = B(P) (4^0.7 - 1). The script prints it beside the means (sharp
caustic edges and corners make the power law approximate: read it as the bias's size, not a
correction to the last digit), and the standard error of the seeds' mean.

Both renderers count paths without a depth bound (Tungsten's max_bounces 64 for each subpath,
the farm's --max-depth -1): at the shared reference's 8 edges, a photon mapper's camera and
photon subpaths of up to 8 bounces each keep longer paths than the farm's 8 edges, and each of
the water's crossings is an edge. Lax shading normals on both sides (Tungsten's own). Below index
1.001 the room without its water is the limit (bench/water_index.py), which the farm's bdpt
renders with no photon mapping's bias: a check of the reference itself (--dry-seconds).

Then the farm's algorithm renders each index for each of SECONDS at each seed, and the script
prints its channel means against the reference and its relative MSE (per pixel, and over 4x4
blocks: photon mapping blurs the sharpest caustic edges by about a pixel), over the pixels that are
neither among the reference's brightest 0.1% nor next to one (the light seen directly or in the
water, which each renderer's pixel filter spreads its own way; see kept()).

Tungsten at 88ea020 dies of a segfault in most photon-mapping renders of more than a few dozen
passes: the faulting load is PhotonMapIntegrator::tracePhotons's read of its task group
(`_group->isAborting()`), which the progressive integrator's startRender assigns only after it
has enqueued the pass that reads it (likely a race on that member). Build the anchor with both
reads taken out (the renderer is never aborted here, so nothing else changes), then as the
anchors' README says:

  sed -i 's|if (_group->isAborting())|if (false)|' \
      TUNGSTEN_SRC/src/core/integrators/photon_map/PhotonMapIntegrator.cpp

A render that dies anyway is run again, up to six times.
"""
import argparse
import json
import os
import subprocess
import sys
import time
import importlib.util

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import water_index  # noqa: E402  (the scene's variants and the farm's render)

SHARED_TOOLS = os.path.join(water_index.SHARED, 'tools')
_spec = importlib.util.spec_from_file_location('m2t', os.path.join(SHARED_TOOLS, 'mitsuba2tungsten.py'))
m2t = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(m2t)

ALPHA = 0.3


def tungsten_json(xml, out, size, passes, photons, radius):
    m2t.convert(xml, out, os.path.dirname(os.path.abspath(xml)) + '/')
    d = json.load(open(out))
    d['camera']['resolution'] = [size, size]
    d['integrator'] = {'type': 'progressive_photon_map', 'min_bounces': 0, 'max_bounces': 64,
                       'enable_two_sided_shading': True, 'enable_consistency_checks': False,
                       'photon_count': photons, 'gather_radius': radius,
                       'gather_photon_count': 1 << 20, 'alpha': ALPHA}
    stem = os.path.abspath(os.path.splitext(out)[0])  # Tungsten reads paths from the scene's folder
    d['renderer'].update(output_file=stem + '.png', hdr_output_file=stem + '.pfm', spp=passes,
                         spp_step=1, timeout='0', checkpoint_interval='0')
    json.dump(d, open(out, 'w'), indent=1)
    return stem + '.pfm'


def photon_map(tungsten, xml, folder, size, passes, photons, radius, seed):
    js = os.path.join(folder, f'ppm-{size}-{passes}x{photons}-r{radius:g}-seed{seed}.json')
    pfm = tungsten_json(xml, js, size, passes, photons, radius)
    if not os.path.exists(pfm):
        began = time.time()
        command = [tungsten, '-t', '2', '--seed', str(seed), js]
        for attempt in range(6):
            done = subprocess.run(command, capture_output=True, text=True)
            if done.returncode == 0 and os.path.exists(pfm):
                break
            print(f'# {js}: tungsten exited with {done.returncode}; again', file=sys.stderr, flush=True)
        else:
            raise SystemExit(f'{js}: tungsten failed: {(done.stdout + done.stderr)[-600:]}')
        print(f'# {pfm}: {time.time() - began:.0f} s', file=sys.stderr, flush=True)
    return water_index.load(pfm)


def kept(reference):
    """The pixels to compare: none that is among the reference's brightest 0.1% or next to one
    (the light seen directly or in the water, which each renderer's pixel filter spreads its own
    way: Tungsten's tent over two pixels, the farm's box over one). Chosen from the reference
    alone: a mask that also took the compared image's brightest pixels would drop its noise's
    highest values and bias its mean low (about 1% at index 1.5 after 60 s)."""
    bright = (reference >= np.percentile(reference, 99.9)).any(axis=2)
    near = bright.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near |= np.roll(np.roll(bright, dy, axis=0), dx, axis=1)
    return ~near


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('out')
    ap.add_argument('--tungsten', required=True)
    ap.add_argument('--farm', default=os.path.join(water_index.ROOT, 'build', 'bin', 'farm'))
    ap.add_argument('--indices', default='1.1,1.33,1.5,1.8,2.4,4')
    ap.add_argument('--passes', type=int, default=64)
    ap.add_argument('--ppm-seeds', type=int, default=3)
    ap.add_argument('--photons', type=int, default=1000000)
    ap.add_argument('--radius', type=float, default=0.05)
    ap.add_argument('--size', type=int, default=128)
    ap.add_argument('--algorithm', default='mlt')
    ap.add_argument('--seconds', default='30,60,120')
    ap.add_argument('--seeds', default='1-3')
    ap.add_argument('--reference-only', action='store_true')
    ap.add_argument('--bootstrap-candidates', type=int, default=0,
                    help="the farm's bootstrap size (0: its default, sized to the job)")
    ap.add_argument('--dry-seconds', type=float, default=120,
                    help='at an index under 1.001, also bdpt on the room without its water')
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    print(f'photon mapping: {a.ppm_seeds} x {a.passes} passes of {a.photons} photons, radius '
          f'{a.radius:g}, alpha {ALPHA}; {a.algorithm} at {a.seconds} s; unbounded depth, '
          f'{a.size}x{a.size}, lax normals')
    print('index,render,seconds,seed,mean R %,mean G %,mean B %,relMSE,relMSE of 4x4 blocks')
    for index in a.indices.split(','):
        # The shipped index (1.8) written as 1.80: a copy of the scene, which variant() insists on.
        shipped = index.rstrip('0').rstrip('.') == '1.8'
        xml = water_index.variant(os.path.join(a.out, 'scenes'), index,
                                  water_index.at_index('1.80' if shipped else index))
        folder = os.path.join(a.out, index)  # renders kept across runs (variant() starts afresh)
        os.makedirs(folder, exist_ok=True)
        runs = [photon_map(a.tungsten, xml, folder, a.size, a.passes, a.photons, a.radius, seed)
                for seed in range(1, a.ppm_seeds + 1)]
        short = photon_map(a.tungsten, xml, folder, a.size, a.passes // 4, a.photons, a.radius, 1)
        ref_image = sum(runs) / len(runs)
        keep = kept(ref_image)
        ref = ref_image[keep].mean(axis=0)

        def pct(image):  # each channel's mean against the reference's, in percent
            return list(100 * (image[keep].mean(axis=0) / ref - 1))

        seed_means = np.array([r[keep].mean(axis=0) for r in runs])
        error = 100 * seed_means.std(axis=0, ddof=1) / np.sqrt(len(runs)) / ref
        # B(P) = (I(P/4) - I(P)) / (4^0.7 - 1), both of the first seed
        bias = 100 * (short[keep].mean(axis=0) - runs[0][keep].mean(axis=0)) / (
            4 ** (1 - ALPHA) - 1) / ref
        print(f'{index},ppm: standard error of {len(runs)} seeds,,,' +
              ','.join(f'{e:.2f}' for e in error) + ',')
        print(f'{index},ppm: its bias at {a.passes} passes,,,' +
              ','.join(f'{b:+.2f}' for b in bias) + ',', flush=True)
        np.save(os.path.join(folder, 'reference.npy'), ref_image)
        if float(index) < 1.001 and a.dry_seconds > 0:
            # Near index 1 the room without its water is the limit (bench/water_index.py), and
            # bdpt renders it with no photon mapping's bias: a check of the reference itself.
            dry_xml = water_index.variant(os.path.join(a.out, 'scenes'), 'dry',
                                          water_index.without_water)
            dry = sum(water_index.load(water_index.render(
                a.farm, dry_xml, 'bdpt', a.dry_seconds, seed, -1, a.size,
                os.path.join(a.out, f'dry-bdpt-{a.size}-{a.dry_seconds:g}s-{seed}.exr')))
                for seed in (1, 2)) / 2
            print(f'{index},dry room bdpt 2x{a.dry_seconds:g}s,,,' +
                  ','.join(f'{d:+.2f}' for d in pct(dry)) + ',', flush=True)
        if a.reference_only:
            continue
        for seconds in a.seconds.split(','):
            for seed in water_index.seed_list(a.seeds):
                z = f'-z{a.bootstrap_candidates}' if a.bootstrap_candidates else ''
                extra = ('--bootstrap-candidates', str(a.bootstrap_candidates)) if z else ()
                image = water_index.load(water_index.render(
                    a.farm, xml, a.algorithm, float(seconds), seed, -1, a.size,
                    os.path.join(folder, f'{a.algorithm}-{a.size}-{seconds}s{z}-{seed}.exr'), extra))
                both = keep
                rel = float((((image - ref_image) ** 2)[both] / (ref_image[both] ** 2 + 1e-2)).mean())
                # Over 4x4 blocks (the light's blocks left out): photon mapping blurs sharp
                # caustic edges by its gather radius, about a pixel at 128x128 after 64 passes.
                n = a.size // 4
                blocks = lambda x: x[:4 * n, :4 * n].reshape(n, 4, n, 4, -1).mean(axis=(1, 3))  # noqa
                block_keep = blocks(both[..., None].astype(float))[..., 0] == 1
                bi, br = blocks(image)[block_keep], blocks(ref_image)[block_keep]
                rel4 = float((((bi - br) ** 2) / (br ** 2 + 1e-2)).mean())
                print(f'{index},{a.algorithm}{z},{seconds},{seed},' +
                      ','.join(f'{d:+.2f}' for d in pct(image)) + f',{rel:.4g},{rel4:.4g}',
                      flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
