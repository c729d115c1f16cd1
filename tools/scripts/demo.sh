#!/usr/bin/env bash
# The main job, end to end: install, build, then
#   - generate a thesis-style synthetic sequence (a ~200-point hand-drawn-like
#     curve translated by up to +-4 px per frame, 30% salt-and-pepper noise),
#   - build a table from its model image (1-pixel cells over +-5 px),
#   - track the sequence and compare with the ground truth,
# printing accuracy and per-frame time. Output stays in build/demo/.
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/setup-debian.sh
cmake --preset release >/dev/null
cmake --build --preset release
g=build/release/tools/gabarit
out=build/demo
noise=${NOISE:-0.3}
rm -rf "$out" && mkdir -p "$out"
$g synth --shape random --points 200 --frames 300 --max-step 4 --noise "$noise" --seed 1 -o "$out/seq"
$g tables build --model "$out/seq/model.pgm" --binary --x -5:5:11 --y -5:5:11 -o "$out/table.gbt"
init=$(sed -n 2p "$out/seq/gt.csv" | cut -d, -f2,3)
$g track --table "$out/table.gbt" --frames "$out/seq/frames.y4m" --init "$init" -o "$out/poses.csv" --stats "$out/stats.json"
$g eval --poses "$out/poses.csv" --gt "$out/seq/gt.csv" > "$out/accuracy.json"
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
a = json.load(open(f"{out}/accuracy.json"))
s = json.load(open(f"{out}/stats.json"))
t = s["per_frame_us"]
print(f"\naccuracy: {a['exact']}/{a['frames']} frames on the exact pixel, {a['wrong']} wrong, "
      f"mean error {a['mean_error_px']:.3f} px, max {a['max_error_px']:.3f} px")
print(f"per frame: {t['mean']:.1f} us mean, {t['p50']:.1f} p50, {t['p99']:.1f} p99, {t['max']:.1f} max "
      f"({s['features_per_frame']:.0f} features, {s['votes_per_frame']:.0f} votes); table {s['table_bytes']} bytes, {s['cells']} cells")
print(f"files: {out}/poses.csv {out}/stats.json {out}/accuracy.json")
PY
