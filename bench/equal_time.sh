#!/usr/bin/env bash
# Every algorithm at equal wall-clock time on the shared scenes, at the references' sizes, in this
# process with two threads: relative MSE against the independent reference, the deviation of the
# channel means (imgcmp.py's capped means), work per second and, for the Markov chains, the
# acceptance of each kind of proposal. Writes OUT/<scene>-<algorithm>/ (image, report) and
# OUT/table.md.
#   bench/equal_time.sh [SECONDS] [OUT] [ALGORITHMS] [SCENES]
# A scene is NAME:WIDTH (../shared/scenes/NAME/scene.xml against ../shared/references/
# NAME-WIDTH.exr) or NAME:WIDTH:SCENE_FILE:REFERENCE, e.g. the pbrt door scene against the long
# BDPT render kept in the repository:
#   bench/equal_time.sh 30 out/ajar "" \
#     veach-ajar:256:../shared/scenes/veach-ajar/scene.pbrt:tests/data/veach-ajar-bdpt-256.exr
# Run it alone: timings taken beside a build are noise.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
out=${2:-out/equal-time}
algorithms=${3:-"pt bdpt pssmlt pssmlt-pt mmlt mlt erpt"}
[ -n "$algorithms" ] || algorithms="pt bdpt pssmlt pssmlt-pt mmlt mlt erpt"
scenes=${4:-"cornell-box:256 veach-mis:320 veach-bidir:256 water-caustic:256"}
shared=${FARM_SHARED_DIR:-../shared}
mkdir -p "$out"
for entry in $scenes; do
  IFS=: read -r scene width sceneFile reference <<< "$entry"
  sceneFile=${sceneFile:-$shared/scenes/$scene/scene.xml}
  reference=${reference:-$shared/references/$scene-$width.exr}
  for algorithm in $algorithms; do
    dir="$out/$scene-$algorithm"
    mkdir -p "$dir"
    build/bin/farm render "$sceneFile" --width "$width" \
      --algorithm "$algorithm" --time "$seconds" --seed 1 --threads 2 \
      --reference "$reference" --report "$dir" -o "$dir/image.exr" \
      > "$dir/log.txt" 2>&1
    /usr/bin/python3 "$shared/tools/imgcmp.py" "$dir/image.exr" "$reference" \
      > "$dir/imgcmp.txt" 2>&1 || true
  done
done
/usr/bin/python3 - "$out" "$algorithms" "$scenes" <<'EOF'
import json, re, sys
out, algorithms, scenes = sys.argv[1], sys.argv[2].split(), sys.argv[3].split()
rows = ["| scene | algorithm | relMSE | channel means vs reference | work/s | acceptance |",
        "|---|---|---|---|---|---|"]
for entry in scenes:
    scene = entry.split(":")[0]
    for a in algorithms:
        d = f"{out}/{scene}-{a}"
        try:
            r = json.load(open(f"{d}/report.json"))
        except (OSError, ValueError):
            rows.append(f"| {scene} | {a} | failed: see {d}/log.txt | | | |")
            continue
        dev = re.search(r"dev \[([^\]]*)\]", open(f"{d}/imgcmp.txt").read())
        means = re.search(r"means \[([^\]]*)\] ref \[([^\]]*)\]", open(f"{d}/imgcmp.txt").read())
        if means:
            m = [float(x) for x in means.group(1).split(",")]
            ref = [float(x) for x in means.group(2).split(",")]
            devs = ", ".join(f"{100 * (x / y - 1):+.1f}%" for x, y in zip(m, ref))
        else:
            devs = "?"
        accept = ", ".join(f"{k} {100 * v['acceptance']:.0f}%"
                           for k, v in r.get("mutations", {}).items())
        unit = "seeds" if a == "erpt" else ("mutations" if "mlt" in a else "samples")
        rows.append(f"| {scene} | {a} | {r['relmse']:.4g} | {devs} | "
                    f"{r['samples_per_second'] / 1e3:.0f}k {unit} | {accept} |")
open(f"{out}/table.md", "w").write("\n".join(rows) + "\n")
print("\n".join(rows))
EOF
