#!/usr/bin/env bash
# --algorithm auto against every algorithm, on each shared scene, against the references:
# relative MSE at 10, 30 and 100 seconds (issue 9's measure). Every algorithm renders once for
# the longest budget (farm compare; its error at the shorter times is read off its series, at
# the last flush before each); auto renders once per budget, since its pilot takes a share of
# the budget. Writes OUT/<scene>/ (compare reports, auto-<seconds>/) and OUT/table.md.
#   bench/auto_vs_best.sh [OUT] [SECONDS...]     (default out/auto-vs-best 10 30 100)
# Run it alone: timings beside a build are noise. About 14 minutes a scene at the defaults;
# ONLY_SCENE=NAME runs one scene, AUTO_ONLY=1 only auto (the algorithms' series kept).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/auto-vs-best}
shift || true
times=("$@")
[ ${#times[@]} -gt 0 ] || times=(10 30 100)
longest=${times[-1]}
shared=${FARM_SHARED_DIR:-../shared}
algorithms=pt,bdpt,pssmlt,pssmlt-pt,mmlt,mlt,erpt
# scene  scene file  reference  width height  [flags that make the reference's integral]
# The water-caustic reference keeps paths whose sides its normals dispute (lax) and has at most
# 8 edges where the file says strict and 9 (docs/conventions.md):
# against the file's own settings its relative MSE would carry that 3-10% difference of means.
scenes=(
  "cornell-box $shared/scenes/cornell-box/scene.xml $shared/references/cornell-box-256.exr 256 256"
  "veach-bidir $shared/scenes/veach-bidir/scene.xml $shared/references/veach-bidir-256.exr 256 256"
  "veach-mis $shared/scenes/veach-mis/scene.xml $shared/references/veach-mis-320.exr 320 180"
  "water-caustic $shared/scenes/water-caustic/scene.xml $shared/references/water-caustic-256.exr 256 256 --shading-normals lax --max-depth 8"
  "veach-ajar $shared/scenes/veach-ajar/scene.pbrt tests/data/veach-ajar-bdpt-256.exr 256 144"
)
mkdir -p "$out"
for entry in "${scenes[@]}"; do
  read -r name scene reference width height rest <<< "$entry"
  read -r -a flags <<< "${rest:-}"
  [ -n "${ONLY_SCENE:-}" ] && [ "$ONLY_SCENE" != "$name" ] && continue
  dir="$out/$name"
  mkdir -p "$dir"
  # AUTO_ONLY=1: keep the algorithms' series from an earlier run, render auto again.
  [ -n "${AUTO_ONLY:-}" ] || build/bin/farm compare "$scene" --algorithms "$algorithms" --time "$longest" \
    --width "$width" --height "$height" --seed 1 --reference "$reference" --report "$dir" \
    "${flags[@]}" > "$dir/compare.log" 2>&1 || echo "$name: compare failed (see $dir/compare.log)"
  for t in "${times[@]}"; do
    build/bin/farm render "$scene" --algorithm auto --time "$t" --width "$width" \
      --height "$height" --seed 1 --reference "$reference" --report "$dir/auto-$t" "${flags[@]}" \
      -o "$dir/auto-$t.exr" > "$dir/auto-$t.log" 2>&1 || echo "$name: auto at $t s failed (see $dir/auto-$t.log)"
  done
done
python3 - "$out" "${times[@]}" <<'EOF'
import json, os, sys
sys.path.insert(0, "bench")
from corpus_table import at, series  # relative MSE series and their value at a time
out, times = sys.argv[1], [float(t) for t in sys.argv[2:]]
algorithms = "pt,bdpt,pssmlt,pssmlt-pt,mmlt,mlt,erpt".split(",")

lines = ["| scene | seconds | " + " | ".join(algorithms) + " | best | auto (pick) | auto / best |",
         "|---|---|" + "---|" * (len(algorithms) + 3)]
for name in sorted(os.listdir(out)):
    d = os.path.join(out, name)
    if not os.path.isdir(d):
        continue
    for t in times:
        row = {}
        for a in algorithms:
            p = os.path.join(d, a, "error_vs_time.csv")
            if os.path.exists(p):
                row[a] = at(series(p), t)
        auto = os.path.join(d, "auto-%g" % t)
        autoErr, pick = None, "?"
        if os.path.exists(os.path.join(auto, "error_vs_time.csv")):
            s = series(os.path.join(auto, "error_vs_time.csv"))
            autoErr = s[-1][1] if s else None
            with open(os.path.join(auto, "report.json")) as f:
                pick = json.load(f).get("algorithm", "?")
        known = {a: e for a, e in row.items() if e is not None}
        best = min(known, key=known.get) if known else None
        cells = ["%.4g" % row[a] if row.get(a) is not None else "-" for a in algorithms]
        ratio = autoErr / known[best] if best and autoErr else None
        lines.append("| %s | %g | %s | %s | %s | %s |" % (
            name, t, " | ".join(cells), best or "-",
            ("%.4g (%s)" % (autoErr, pick)) if autoErr is not None else "-",
            "%.2f" % ratio if ratio else "-"))
table = "\n".join(lines) + "\n"
open(os.path.join(out, "table.md"), "w").write(table)
print(table)
EOF
