#!/usr/bin/env bash
# The farm's figures on one machine (issue 8), each from log time stamps:
#  - one against two worker processes on the same job and seed, with and without batches
#    (--batch-window 0 and 1): end-to-end time, work per second, each worker's closing line
#    (uploads, share of chain time spent streaming), and the images compared;
#  - a worker killed (-9) while it holds a chain: seconds until the lease expires and another
#    worker leases the chain, at --lease-seconds 5 and at the default 30;
#  - a durable coordinator killed (-9) under two jobs and two workers: seconds until the new one
#    serves, and until every worker thread runs a chain again.
#   bench/farm_recovery.sh [OUT]
# Run it alone: timings taken beside a build are noise.
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/farm-recovery}
B=build/bin
S=../shared/scenes/cornell-box/scene.xml
rm -rf "$out" && mkdir -p "$out"
stamp() { grep -h "$2" "$1" | head -1 | sed -E 's/^\[([^]]*)\].*/\1/'; }
seconds() { date -d "$1" +%s.%N; }
since() { python3 -c "import sys; print('%.2f' % (float(sys.argv[2]) - float(sys.argv[1])))" "$1" "$2"; }
port=$((52000 + RANDOM % 4000))

echo "== one against two worker processes (pssmlt 256x256, 128 per pixel, 8 chains, 2 threads)"
for window in 0 1; do
  for mode in one two; do
    port=$((port + 1))
    $B/farm-coordinator --listen 127.0.0.1:$port > "$out/c-$window-$mode.log" 2>&1 &
    coordinator=$!
    sleep 0.5
    workers=()
    if [ $mode = one ]; then
      $B/farm-worker --coordinator 127.0.0.1:$port --threads 2 --batch-window $window \
        --cache "$out/cache" > "$out/w-$window-$mode-1.log" 2>&1 &
      workers+=($!)
    else
      for i in 1 2; do
        $B/farm-worker --coordinator 127.0.0.1:$port --threads 1 --batch-window $window \
          --cache "$out/cache" > "$out/w-$window-$mode-$i.log" 2>&1 &
        workers+=($!)
      done
    fi
    t0=$(date +%s.%N)
    job=$($B/farm submit --coordinator 127.0.0.1:$port $S --algorithm pssmlt --width 256 \
      --height 256 --mpp 128 --chains 8 2>/dev/null | tail -1)
    $B/farm fetch --coordinator 127.0.0.1:$port "$job" -o "$out/image-$window-$mode.exr" \
      --timeout 900 > /dev/null 2>&1
    t1=$(date +%s.%N)
    kill "${workers[@]}" 2>/dev/null; wait "${workers[@]}" 2>/dev/null
    rate=$($B/farm status --coordinator 127.0.0.1:$port "$job" --json 2>/dev/null |
      python3 -c "import json,sys; print('%.0f' % json.load(sys.stdin)['samples_per_second'])")
    kill $coordinator; wait $coordinator 2>/dev/null
    echo "batch window $window, $mode process(es): $(since $t0 $t1) s end to end, $rate mutations/s"
    grep -h "done:" "$out"/w-$window-$mode-*.log | sed 's/.*done: /  /'
  done
done
/usr/bin/python3 ../shared/tools/imgcmp.py "$out/image-0-one.exr" "$out/image-1-one.exr" | tail -1

for lease in 5 30; do
  echo "== a worker killed while it holds a chain (--lease-seconds $lease; 3 workers, 2 chains)"
  port=$((port + 1))
  $B/farm-coordinator --listen 127.0.0.1:$port --lease-seconds $lease > "$out/c-lease$lease.log" 2>&1 &
  coordinator=$!
  sleep 0.5
  pids=()
  for i in 1 2 3; do
    $B/farm-worker --coordinator 127.0.0.1:$port --threads 1 --cache "$out/cache" \
      > "$out/w-lease$lease-$i.log" 2>&1 &
    pids+=($!)
  done
  job=$($B/farm submit --coordinator 127.0.0.1:$port $S --algorithm pt --width 256 --height 256 \
    --spp 100000 --chains 2 2>/dev/null | tail -1)
  for _ in $(seq 100); do
    [ "$(grep -l " leased" "$out"/w-lease$lease-*.log 2>/dev/null | wc -l)" = 2 ] && break
    sleep 0.1
  done
  sleep 3
  victim=$(grep -l " leased" "$out"/w-lease$lease-*.log | head -1)
  index=${victim##*-}; index=${index%.log}
  kill -9 "${pids[$((index - 1))]}"; killed=$(date +%s.%N)
  for _ in $(seq $((lease * 20 + 200))); do
    [ "$(grep -l " leased" "$out"/w-lease$lease-*.log | wc -l)" = 3 ] && break
    sleep 0.05
  done
  third=""
  for f in "$out"/w-lease$lease-*.log; do
    [ "$f" != "$victim" ] && [ "$(grep -c " leased" "$f")" -gt 0 ] &&
      [ "$(seconds "$(stamp "$f" " leased")")" \> "$killed" ] && third=$f
  done
  expired=$(seconds "$(stamp "$out/c-lease$lease.log" "expired")")
  again=$(seconds "$(stamp "$third" " leased")")
  echo "killed -> lease expired: $(since $killed $expired) s; -> leased to another worker: $(since $killed $again) s"
  $B/farm cancel --coordinator 127.0.0.1:$port "$job" > /dev/null 2>&1
  kill "${pids[@]}" $coordinator 2>/dev/null; wait 2>/dev/null
done

echo "== a durable coordinator killed under two jobs of 4 chains and 2 workers x 2 threads"
port=$((port + 1))
$B/farm-coordinator --listen 127.0.0.1:$port --data "$out/data" > "$out/r1.log" 2>&1 &
coordinator=$!
sleep 0.5
pids=()
for i in 1 2; do
  $B/farm-worker --coordinator 127.0.0.1:$port --threads 2 --cache "$out/cache" \
    > "$out/wr$i.log" 2>&1 &
  pids+=($!)
done
j1=$($B/farm submit --coordinator 127.0.0.1:$port $S --algorithm pssmlt --width 256 --height 256 \
  --mpp 4096 --chains 4 2>/dev/null | tail -1)
j2=$($B/farm submit --coordinator 127.0.0.1:$port $S --algorithm pt --width 256 --height 256 \
  --spp 100000 --chains 4 2>/dev/null | tail -1)
sleep 15
kill -9 $coordinator; killed=$(date +%s.%N); wait $coordinator 2>/dev/null
$B/farm-coordinator --listen 127.0.0.1:$port --data "$out/data" > "$out/r2.log" 2>&1 &
coordinator=$!
after() { cat "$out"/wr*.log | grep " leased" | sed -E 's/^\[([^]]*)\].*/\1/' |
  while read -r t; do s=$(seconds "$t"); [ "$s" \> "$killed" ] && echo "$s"; done | sort; }
for _ in $(seq 600); do [ "$(after | wc -l)" -ge 4 ] && break; sleep 0.05; done
serving=$(seconds "$(stamp "$out/r2.log" "remembered")")
echo "killed -> the new coordinator serves: $(since $killed $serving) s; -> all 4 worker threads run chains again: $(since $killed "$(after | sed -n 4p)") s"
grep -h "resumed" "$out/r2.log" | sed 's/.*job /  job /'
$B/farm cancel --coordinator 127.0.0.1:$port "$j1" > /dev/null 2>&1
$B/farm cancel --coordinator 127.0.0.1:$port "$j2" > /dev/null 2>&1
kill "${pids[@]}" $coordinator 2>/dev/null; wait 2>/dev/null
