#!/usr/bin/env bash
# Do mlt and BDPT agree on the water caustic when BDPT converges there too? The scene with its
# light 200 times wider and deeper (1 m by 0.8 m, radiance / 4e4: the same power), as in
# ManifoldNextEvent.TakesOverWhatBdptCarriesUnderTheWaterCausticsWaves, so that BDPT's camera
# paths reach the light through the water. Lax normals and 8 edges, as the reference's renderer
# had them. Each algorithm renders once per seed; the table compares each with bdpt: channel
# means, and the mean of each of BLOCKS x BLOCKS blocks of the film with a standard error from
# the spread between seeds (few seeds: few degrees of freedom, read the z loosely), and the
# same for three bands of rows (above the water, the surface seen from below, under the water).
#   bench/water_wide_light.sh [SECONDS] [OUT] [SEEDS...]   (default 40 out/water-wide 1 2 3 4 5)
# ALGS="mlt bdpt" (default) names what renders; bdpt must be among them. EXTRA="--chains 1024"
# passes more options to every algorithm but bdpt, TAG (say "_c1024") names those runs. BLOCKS=8
# by default.
# Run it alone: timings beside a build are noise. About 2 x SECONDS a seed.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-40}
out=${2:-out/water-wide}
shift 2 || shift $#
seeds=("$@")
[ ${#seeds[@]} -gt 0 ] || seeds=(1 2 3 4 5)
shared=${FARM_SHARED_DIR:-../shared}
read -r -a algs <<< "${ALGS:-mlt bdpt}"
read -r -a extra <<< "${EXTRA:-}"
tag=${TAG:-}
mkdir -p "$out"
scene="$out/scene.xml"
ln -sfn "$(realpath "$shared/scenes/water-caustic/models")" "$out/models"
# The light's rectangle: its two half-extents (the matrix's first two columns) times 200.
sed -e 's|<matrix value="-0.0025 1.91069e-015 -4.37114e-008 -0.005 2.18557e-010 2.18557e-008 -0.5 1.98 0 -0.002 -8.74228e-011 -0.03 0 0 0 1"/>|<matrix value="-0.5 3.82138e-013 -4.37114e-008 -0.005 4.37114e-008 4.37114e-006 -0.5 1.98 0 -0.4 -8.74228e-011 -0.03 0 0 0 1"/>|' \
  -e 's|<rgb name="radiance" value="541127, 381972, 127324"/>|<rgb name="radiance" value="13.528175, 9.5493, 3.1831"/>|' \
  "$shared/scenes/water-caustic/scene.xml" > "$scene"
if ! grep -q '13.528175' "$scene" || ! grep -q '"-0.5 3.82138e-013' "$scene"; then
  echo "the scene file's light is not the one this script widens" >&2
  exit 1
fi
for seed in "${seeds[@]}"; do
  for a in "${algs[@]}"; do
    opts=()
    name=$a
    if [ "$a" != bdpt ]; then
      opts=("${extra[@]}")
      name=$a$tag
    fi
    build/bin/farm render "$scene" --algorithm "$a" --shading-normals lax --max-depth 8 \
      --width 128 --height 128 --time "$seconds" --seed "$seed" "${opts[@]}" \
      -o "$out/$name-$seed.exr" > "$out/$name-$seed.log" 2>&1 || echo "$name seed $seed failed"
  done
done
/usr/bin/python3 - "$out" "${BLOCKS:-8}" <<'EOF'
import glob, os, re, sys
import numpy as np
import OpenImageIO as oiio
out, nb = sys.argv[1], int(sys.argv[2])
w = np.array([0.212671, 0.715160, 0.072169])

def load(p):
    i = oiio.ImageInput.open(p)
    a = np.array(i.read_image(format="float"))[:, :, :3].astype(np.float64)
    i.close()
    return a

def blocks(a):
    L = a @ w
    h, wd = L.shape
    return np.array([[L[y * h // nb:(y + 1) * h // nb, x * wd // nb:(x + 1) * wd // nb].mean()
                      for x in range(nb)] for y in range(nb)])

sets = {}
for f in sorted(glob.glob(f"{out}/*-*.exr")):
    sets.setdefault(re.sub(r"-\d+\.exr$", "", os.path.basename(f)), []).append(load(f))
base = sets.pop("bdpt")
bb = np.array([blocks(a) for a in base])
cb = np.array([a.mean((0, 1)) for a in base])
np.set_printoptions(linewidth=200, precision=2, suppress=True)
for name, imgs in sorted(sets.items()):
    ba = np.array([blocks(a) for a in imgs])
    ca = np.array([a.mean((0, 1)) for a in imgs])
    se = lambda v: v.std(0, ddof=1) / np.sqrt(len(v))
    rel = (ca.mean(0) / cb.mean(0) - 1) * 100
    relse = np.hypot(se(ca) / ca.mean(0), se(cb) / cb.mean(0)) * 100
    z = (ba.mean(0) - bb.mean(0)) / np.hypot(se(ba), se(bb))
    print(f"{name} ({len(imgs)} renders) against bdpt ({len(base)}): channel means {rel.round(3)}%"
          f" +- {relse.round(3)}%")
    print(f"  blocks, {name} / bdpt - 1 (%):")
    print((ba.mean(0) / bb.mean(0) - 1) * 100)
    print("  z:")
    print(z)
    print(f"  chi2 / dof {(z ** 2).mean():.2f}, largest |z| {np.abs(z).max():.2f}")
    # Bands of rows: the light and walls above the water, the surface seen from below, and
    # what lies under the water (seen through its front), each as one luminance mean.
    h = imgs[0].shape[0]
    for band, (a, b) in {"above the water": (0, h // 4), "the surface": (h // 4, 3 * h // 8),
                         "under the water": (3 * h // 8, h)}.items():
        va = np.array([(i[a:b] @ w).mean() for i in imgs])
        vb = np.array([(i[a:b] @ w).mean() for i in base])
        print(f"  {band} (rows {a}-{b}): {(va.mean() / vb.mean() - 1) * 100:+.2f}%"
              f" +- {np.hypot(se(va) / va.mean(), se(vb) / vb.mean()) * 100:.2f}%")
EOF
