#!/bin/bash
# Issue 45, part 3: the rate of one thread against two threads of one process (`farm render
# --threads 2`) and two single-thread worker processes on one coordinator (`farm-worker
# --threads 1`, twice), per algorithm, on the Cornell box at 256x256 with a fixed budget (the
# same work each time). Prints the work per second each reports (its work over its rendering
# time), the mean of REPEATS runs taken in turn, and the ratios to one thread.
#   bench/thread_scaling.sh [BUILD_BIN_DIR] [REPEATS]
# Run it on a machine to itself: anything else on the cores shows up in the two-way figures.
set -euo pipefail
bin=${1:-build/bin}
repeats=${2:-2}
scene=${FARM_SHARED_DIR:-../shared}/scenes/cornell-box/scene.xml
out=$(mktemp -d)
trap 'rm -rf "$out"; kill $(jobs -p) 2>/dev/null || true' EXIT
options=(--width 256 --height 256 --seed 5)
rate_of() {  # a render's report on stdin -> its work per second
  sed -n 's/^  \(mutations\|samples\|seeds\): [0-9]* ([0-9.]* per pixel), \([0-9.]*\)\([kM]\)\/s.*/\2 \3/p' |
    awk '{print $1 * ($2 == "M" ? 1e6 : 1e3)}'
}
threads() {  # algorithm budget-flag budget threads
  "$bin/farm" render "$scene" --algorithm "$1" "$2" "$3" "${options[@]}" --threads "$4" \
    -o "$out/x.exr" 2>&1 | rate_of
}
processes() {  # algorithm budget-flag budget processes
  local port=$((52000 + RANDOM % 8000)) pids=() job
  "$bin/farm-coordinator" --listen 127.0.0.1:$port > "$out/coordinator.log" 2>&1 &
  pids+=($!)
  sleep 0.5
  for ((i = 0; i < $4; ++i)); do
    "$bin/farm-worker" --coordinator 127.0.0.1:$port --threads 1 --cache "$out/cache" \
      > "$out/worker-$i.log" 2>&1 &
    pids+=($!)
  done
  job=$("$bin/farm" submit --coordinator 127.0.0.1:$port "$scene" --algorithm "$1" "$2" "$3" \
    "${options[@]}" 2>/dev/null | tail -1)
  "$bin/farm" fetch --coordinator 127.0.0.1:$port "$job" -o "$out/y.exr" 2>&1 | rate_of
  kill "${pids[@]}" 2>/dev/null
  wait "${pids[@]}" 2>/dev/null || true
}
printf '%-8s %12s %12s %7s %12s %7s\n' algorithm "1 thread/s" "2 threads/s" ratio \
  "2 procs/s" ratio
for spec in "pt --spp 96" "bdpt --spp 24" "pssmlt --mpp 24" "mmlt --mpp 160" "mlt --mpp 160" \
            "erpt --spp 2"; do
  set -- $spec
  one=0 two=0 procs=0
  for ((r = 0; r < repeats; ++r)); do
    one=$(awk -v a="$one" -v b="$(threads "$1" "$2" "$3" 1)" 'BEGIN{print a + b}')
    two=$(awk -v a="$two" -v b="$(threads "$1" "$2" "$3" 2)" 'BEGIN{print a + b}')
    procs=$(awk -v a="$procs" -v b="$(processes "$1" "$2" "$3" 2)" 'BEGIN{print a + b}')
  done
  awk -v n="$1" -v a="$one" -v b="$two" -v p="$procs" -v r="$repeats" \
    'BEGIN{printf "%-8s %12.0f %12.0f %7.3f %12.0f %7.3f\n", n, a / r, b / r, b / a, p / r, p / a}'
done
