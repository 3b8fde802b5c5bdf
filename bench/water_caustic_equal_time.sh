#!/usr/bin/env bash
# Issue 7's measure: every algorithm on the water caustic at equal wall-clock time, with and
# without manifold exploration, over several seeds. Shading normals are lax and paths have at
# most 8 edges, as the reference's renderer had them (README, "What it does" on shading
# normals, and docs/conventions.md on the reference's depth: Tungsten's
# max_bounces 8, where the file says 9). A single run's relative MSE there is decided by
# a few dozen pixels (a chain that found a bright caustic spike and stayed, a path tracer's
# firefly), so each algorithm renders once per seed and the table gives, beside each run's
# relative MSE and their mean, what the hot pixels hide: the relative MSE without the 100
# worst pixels, the median pixel's, and the capped channel means against the reference.
#   bench/water_caustic_equal_time.sh [SECONDS] [OUT] [SEEDS...]   (default 30 out/water-caustic 1 2 3)
# ONLY="mlt mmlt" renders those rows alone (the table then lists only them).
# Run it alone: timings taken beside a build are noise. About 8 x SECONDS a seed.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
out=${2:-out/water-caustic}
shift 2 || shift $#
seeds=("$@")
[ ${#seeds[@]} -gt 0 ] || seeds=(1 2 3)
shared=${FARM_SHARED_DIR:-../shared}
scene=$shared/scenes/water-caustic/scene.xml
reference=$shared/references/water-caustic-256.exr
# name and the flags that make it
runs=("pt --algorithm pt" "bdpt --algorithm bdpt" "pssmlt --algorithm pssmlt"
  "pssmlt-pt --algorithm pssmlt-pt" "mmlt --algorithm mmlt" "erpt --algorithm erpt"
  "mlt-no-manifold --algorithm mlt --mutation-mix manifold=0" "mlt --algorithm mlt")
mkdir -p "$out"
for seed in "${seeds[@]}"; do
  for run in "${runs[@]}"; do
    read -r name flags <<< "$run"
    if [ -n "${ONLY:-}" ] && [[ " $ONLY " != *" $name "* ]]; then continue; fi
    dir="$out/$name-$seed"
    mkdir -p "$dir"
    # shellcheck disable=SC2086
    build/bin/farm render "$scene" $flags --shading-normals lax --max-depth 8 --width 256 --height 256 \
      --time "$seconds" --seed "$seed" --threads 2 --reference "$reference" --report "$dir" \
      -o "$dir/image.exr" > "$dir/log.txt" 2>&1 || echo "$name seed $seed failed: see $dir/log.txt"
  done
done
/usr/bin/python3 - "$out" "$reference" "$seconds" "${seeds[@]}" <<'EOF'
import os
import sys
import numpy as np
import OpenImageIO as oiio
out, reference, seconds, seeds = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
names = ["pt", "bdpt", "pssmlt", "pssmlt-pt", "mmlt", "erpt", "mlt-no-manifold", "mlt"]
if os.environ.get("ONLY"):
    names = [n for n in names if n in os.environ["ONLY"].split()]

def load(path):
    return np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT), np.float64)[..., :3]

r = load(reference)
cap = np.percentile(r, 99.9)  # imgcmp.py's capped means
rows = [f"water-caustic, lax normals, 256x256, {seconds} s a run, seeds {' '.join(seeds)}", "",
        "| algorithm | relMSE per seed | mean relMSE | without the 100 worst pixels (mean) "
        "| median pixel (mean) | capped means vs reference (R, G, B; mean over seeds) |",
        "|---|---|---|---|---|---|"]
for name in names:
    rel, trimmed, median, devs = [], [], [], []
    for seed in seeds:
        try:
            x = load(f"{out}/{name}-{seed}/image.exr")
        except Exception:
            continue
        e = (((x - r) ** 2) / (r ** 2 + 1e-2)).mean(axis=2).ravel()
        worst = np.sort(e)[::-1]
        rel.append(e.mean())
        trimmed.append(worst[100:].sum() / e.size)
        median.append(np.median(e))
        devs.append(np.minimum(x, cap).reshape(-1, 3).mean(0) / np.minimum(r, cap).reshape(-1, 3).mean(0) - 1)
    if not rel:
        rows.append(f"| {name} | failed | | | | |")
        continue
    d = np.mean(devs, axis=0)
    rows.append(f"| {name} | {', '.join(f'{v:.3g}' for v in rel)} | {np.mean(rel):.3g} | "
                f"{np.mean(trimmed):.3g} | {np.mean(median):.3g} | "
                f"{', '.join(f'{100 * v:+.1f}%' for v in d)} |")
open(f"{out}/table.md", "w").write("\n".join(rows) + "\n")
print("\n".join(rows))
EOF
