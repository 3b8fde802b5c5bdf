#!/usr/bin/env bash
# One render per seed of each algorithm at equal time, against a reference: where a scene's
# error comes in rare events (a firefly, a chain that holds a bright path for thousands of
# mutations), one render's relative MSE says little, and the table auto_vs_best.sh writes (seed
# 1 alone) can rank two algorithms either way. This gives each algorithm's relative MSE per
# seed, their median (what a render usually gets), their mean (the relative MSE proper, which
# the rare events decide) and how many runs came out over twice the median.
#   bench/seed_spread.sh SCENE REFERENCE SECONDS ALGORITHMS SEEDS [FLAGS...]
#   e.g. bench/seed_spread.sh ../shared/scenes/veach-bidir/scene.xml \
#          ../shared/references/veach-bidir-256.exr 10 bdpt,mmlt "$(seq -s ' ' 1 20)"
# ALGORITHMS: comma-separated; SEEDS: space-separated; FLAGS go to every render (--width and
# --height default to 256). The algorithms alternate seed by seed, so that a drift in the
# machine's speed touches all alike. OUT (default out/seed-spread) keeps each run's log, image
# and report (its relative MSE is report.json's) and the table (table.md). Run it alone:
# timings beside a build are noise. About SECONDS + 1 a run.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 5 ]; then
  sed -n '2,/^[^#]/{/^#/s/^# \{0,1\}//p}' "$0"  # the comment above
  exit 2
fi
scene=$1 reference=$2 seconds=$3 algorithms=$4 seeds=$5
shift 5
flags=("$@")
case " ${flags[*]} " in *" --width "*) ;; *) flags+=(--width 256) ;; esac
case " ${flags[*]} " in *" --height "*) ;; *) flags+=(--height 256) ;; esac
out=${OUT:-out/seed-spread}
mkdir -p "$out"
IFS=, read -r -a algos <<< "$algorithms"
results="$out/results.txt"
: > "$results"
for seed in $seeds; do
  for algo in "${algos[@]}"; do
    run="$out/$algo-$seed"
    if build/bin/farm render "$scene" --algorithm "$algo" --time "$seconds" --seed "$seed" \
      --reference "$reference" --report "$run" -o "$run.exr" "${flags[@]}" > "$run.log" 2>&1; then
      relmse=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["relmse"])' \
        "$run/report.json" 2> /dev/null || true)
      echo "$algo $seed ${relmse:-?}" | tee -a "$results"
    else
      echo "$algo seed $seed failed: see $run.log"
    fi
  done
done
/usr/bin/python3 - "$results" "$seconds" "$algorithms" > "$out/table.md" <<'EOF'
import statistics
import sys
results, seconds, algorithms = sys.argv[1], sys.argv[2], sys.argv[3].split(",")
runs = {a: [] for a in algorithms}
with open(results) as f:
    for line in f:
        algo, seed, value = line.split()
        if value != "?":
            runs[algo].append((int(seed), float(value)))
print("| %s s | runs | median | mean | max (seed) | runs over 2x the median |" % seconds)
print("|---|---|---|---|---|---|")
for a in algorithms:
    v = [e for _, e in runs[a]]
    if not v:
        print("| %s | 0 | | | | |" % a)
        continue
    med = statistics.median(v)
    worst = max(runs[a], key=lambda r: r[1])
    print("| %s | %d | %.4g | %.4g | %.4g (%d) | %d |" % (
        a, len(v), med, statistics.fmean(v), worst[1], worst[0], sum(e > 2 * med for e in v)))
EOF
cat "$out/table.md"
