#!/usr/bin/env bash
# Relative MSE against the independent references at equal wall-clock time, for each algorithm,
# on the Cornell box and the water caustic. Writes OUT/<scene>-<algorithm>/error_vs_time.csv and
# prints the error at a few points in time.
#   bench/error_vs_time.sh [SECONDS] [OUT]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
out=${2:-out/error-vs-time}
shared=${FARM_SHARED_DIR:-../shared}
mkdir -p "$out"
for scene in cornell-box water-caustic; do
  for algorithm in pt bdpt pssmlt; do
    dir="$out/$scene-$algorithm"
    mkdir -p "$dir"
    build/bin/farm render "$shared/scenes/$scene/scene.xml" --width 256 --height 256 \
      --algorithm "$algorithm" --time "$seconds" --seed 1 \
      --reference "$shared/references/$scene-256.exr" --report "$dir" -o "$dir/image.exr" \
      > "$dir/log.txt" 2>&1
    # relMSE at about a quarter, half and all of the budget
    awk -F, -v s="$scene" -v a="$algorithm" -v t="$seconds" '
      NR > 1 { for (i = 1; i <= 3; ++i) if (!done[i] && $1 >= t * i / 4) { r[i] = $4; e[i] = $1; done[i] = 1 }
               last = $4; lastt = $1 }
      END { printf "%-14s %-7s", s, a;
            for (i = 1; i <= 3; ++i) if (done[i]) printf "  relMSE %.4g at %.0fs", r[i], e[i];
            printf "  final %.4g at %.0fs\n", last, lastt }' "$dir/error_vs_time.csv"
  done
done
