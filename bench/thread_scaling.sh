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
# The processes started inside command substitutions are not this shell's jobs: their pids go
# to a file that the exit trap reads.
trap 'xargs -r kill < "$out/pids" 2>/dev/null || true; rm -rf "$out"' EXIT
touch "$out/pids"
options=(--width 256 --height 256 --seed 5)
fail() { echo "thread_scaling.sh: $*" >&2; exit 1; }
rate_of() {  # a render's report on stdin -> its work per second, or nothing
  sed -n 's/^  \(mutations\|samples\|seeds\): [0-9]* ([0-9.]* per pixel), \([0-9.]*\)\([kMG]\{0,1\}\)\/s.*/\2 \3/p' |
    awk '{print $1 * ($2 == "G" ? 1e9 : $2 == "M" ? 1e6 : $2 == "k" ? 1e3 : 1)}'
}
threads() {  # algorithm budget-flag budget threads
  "$bin/farm" render "$scene" --algorithm "$1" "$2" "$3" "${options[@]}" --threads "$4" \
    -o "$out/x.exr" > "$out/render.log" 2>&1 || fail "farm render failed: $(tail -3 "$out/render.log")"
  rate_of < "$out/render.log"
}
processes() {  # algorithm budget-flag budget processes
  local port=$((52000 + RANDOM % 8000)) pids=() job
  "$bin/farm-coordinator" --listen 127.0.0.1:$port > "$out/coordinator.log" 2>&1 &
  pids+=($!)
  echo $! >> "$out/pids"
  for ((i = 0; i < 100; ++i)); do
    grep -q "listening on" "$out/coordinator.log" && break
    sleep 0.1
  done
  grep -q "listening on" "$out/coordinator.log" || fail "the coordinator did not start: $(tail -3 "$out/coordinator.log")"
  for ((i = 0; i < $4; ++i)); do
    "$bin/farm-worker" --coordinator 127.0.0.1:$port --threads 1 --cache "$out/cache" \
      > "$out/worker-$i.log" 2>&1 &
    pids+=($!)
    echo $! >> "$out/pids"
  done
  job=$("$bin/farm" submit --coordinator 127.0.0.1:$port "$scene" --algorithm "$1" "$2" "$3" \
    "${options[@]}" 2> "$out/submit.log" | tail -1)
  [ -n "$job" ] || fail "farm submit failed: $(tail -3 "$out/submit.log")"
  "$bin/farm" fetch --coordinator 127.0.0.1:$port "$job" -o "$out/y.exr" > "$out/fetch.log" 2>&1 ||
    fail "farm fetch failed: $(tail -3 "$out/fetch.log")"
  kill "${pids[@]}" 2>/dev/null
  wait "${pids[@]}" 2>/dev/null || true
  : > "$out/pids"  # reaped: their numbers may be another process's by the exit
  rate_of < "$out/fetch.log"
}
add() {  # running sum, refusing a run that reported no rate
  [ -n "$2" ] || fail "a run reported no work per second (see the logs above)"
  awk -v a="$1" -v b="$2" 'BEGIN{print a + b}'
}
printf '%-8s %12s %12s %7s %12s %7s\n' algorithm "1 thread/s" "2 threads/s" ratio \
  "2 procs/s" ratio
for spec in "pt --spp 96" "bdpt --spp 24" "pssmlt --mpp 24" "mmlt --mpp 160" "mlt --mpp 160" \
            "erpt --spp 2"; do
  set -- $spec
  one=0 two=0 procs=0
  for ((r = 0; r < repeats; ++r)); do
    rate=$(threads "$1" "$2" "$3" 1) || exit 1
    one=$(add "$one" "$rate") || exit 1
    rate=$(threads "$1" "$2" "$3" 2) || exit 1
    two=$(add "$two" "$rate") || exit 1
    rate=$(processes "$1" "$2" "$3" 2) || exit 1
    procs=$(add "$procs" "$rate") || exit 1
  done
  awk -v n="$1" -v a="$one" -v b="$two" -v p="$procs" -v r="$repeats" \
    'BEGIN{printf "%-8s %12.0f %12.0f %7.3f %12.0f %7.3f\n", n, a / r, b / r, b / a, p / r, p / a}'
done
