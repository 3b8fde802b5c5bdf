#!/usr/bin/python3
"""The water caustic's index series references for ctest (WaterIndex, common/render/
water_index_test.cpp), from the photon-mapping references bench/water_ppm.py makes.

  tools/water_index_references.py PPM_OUT [--indices 1.1,1.33,1.5,1.8,2.4,4] [--side 32]

For each index, the mean of PPM_OUT/<index>/ppm-128-64x1000000-r0.05-seed{1,2,3}.pfm (Tungsten's
progressive photon mapper, 64 passes of a million photons, three seeds; docs/specular.md gives
their standard errors and measured bias, at most 0.2% a channel) is averaged over square blocks
of pixels down to SIDE x SIDE and written to tests/data/water-index/<index>.exr. A pixel of the
smaller image is the mean of the block's pixels, as a box-filtered render at that size is, apart
from Tungsten's tent filter (two pixels at 128), which blurs by half a pixel at 32.
"""
import argparse
import os

import numpy as np
import OpenImageIO as oiio

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('ppm_out')
    ap.add_argument('--indices', default='1.1,1.33,1.5,1.8,2.4,4')
    ap.add_argument('--side', type=int, default=32)
    ap.add_argument('--out', default=os.path.join(ROOT, 'tests', 'data', 'water-index'))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    for index in a.indices.split(','):
        images = []
        for seed in (1, 2, 3):
            path = os.path.join(a.ppm_out, index, f'ppm-128-64x1000000-r0.05-seed{seed}.pfm')
            images.append(np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT),
                                     dtype=np.float64)[..., :3])
        mean = sum(images) / len(images)
        block = mean.shape[0] // a.side
        if block * a.side != mean.shape[0] or mean.shape[0] != mean.shape[1]:
            raise SystemExit(f'{index}: {mean.shape[:2]} does not divide into {a.side}')
        small = mean.reshape(a.side, block, a.side, block, 3).mean(axis=(1, 3))
        out = os.path.join(a.out, f'{index}.exr')
        spec = oiio.ImageSpec(a.side, a.side, 3, oiio.FLOAT)
        buf = oiio.ImageBuf(spec)
        buf.set_pixels(oiio.ROI(0, a.side, 0, a.side), small.astype(np.float32))
        if not buf.write(out):
            raise SystemExit(buf.geterror())
        print(f'{out}: mean {small.mean(axis=(0, 1))}')


if __name__ == '__main__':
    main()
