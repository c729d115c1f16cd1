#!/usr/bin/env bash
# The main job, end to end: install, build, then twice
#   - the thesis's synthetic sequence (a ~200-point hand-drawn-like curve
#     translated by up to +-4 px per frame, 30% salt-and-pepper noise), a table
#     from its model image (1-pixel cells over +-5 px);
#   - a grayscale 4-DOF scene of the scene suite (docs/scene-suite.md: a cog
#     cut from a photograph over gravel, a velocity random walk that reverses
#     at the margins, an occluder sliding in from the left, a 3-depth focus
#     stack), a table over x, y +-5 px, theta +-1.5 deg and its 3 depths;
#   - each tracked with gabarit track's defaults (the tracking session) and
#     compared with the ground truth,
# printing accuracy and per-frame time; then the scene suite
# (docs/scene-suite.md: gabarit bench --suite, the default session beside
# the plain loop and the OpenCV NCC bank), printing its summary tables.
# Output stays in build/demo/.
#
# Usage: demo.sh [--gabarit PATH] [--out DIR] [--full-suite]
#   --gabarit PATH  use this gabarit as it is: no install, no build
#                   (the docs.demo test runs the demo so)
#   --out DIR       write into DIR (new or empty) instead of build/demo
#   --full-suite    all 42 scenes of 160 frames (a few minutes) instead of
#                   the quick suite (every 5th scene, 60 frames each)
set -euo pipefail
g="" out="" suite=--quick
while [ $# -gt 0 ]; do
  case "$1" in
    --full-suite) suite=""; shift ;;
    --gabarit) g=$(realpath "${2:?--gabarit needs a path}"); shift 2 ;;
    --out) out=$(realpath -m "${2:?--out needs a folder}"); shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "demo.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
cd "$(dirname "$0")/../.."
if [ -z "$g" ]; then
  bash tools/scripts/setup-debian.sh
  cmake --preset release >/dev/null
  cmake --build --preset release
  g=build/release/tools/gabarit
fi
[ -x "$g" ] || { echo "demo.sh: $g is not an executable gabarit" >&2; exit 2; }
if [ -n "$out" ] && [ -e "$out" ] && [ -n "$(ls -A "$out" 2>/dev/null)" ]; then
  echo "demo.sh: $out exists and is not empty; give a new folder" >&2; exit 2
fi
out=${out:-build/demo}
noise=${NOISE:-0.3}
rm -rf "$out" && mkdir -p "$out"
$g synth --shape random --points 200 --frames 300 --max-step 4 --noise "$noise" --seed 1 -o "$out/seq"
$g tables build --model "$out/seq/model.pgm" --binary --x -5:5:11 --y -5:5:11 -o "$out/table.gbt"
init=$(sed -n 2p "$out/seq/gt.csv" | cut -d, -f2,3)
$g track --table "$out/table.gbt" --frames "$out/seq/frames.y4m" --init "$init" -o "$out/poses.csv" --stats "$out/stats.json"
$g eval --poses "$out/poses.csv" --gt "$out/seq/gt.csv" > "$out/accuracy.json"

s="$out/scene"
$g synth --scene cog --background gravel --motion walk --occlusion-side left --depths 3 --frames 200 --seed 1 -o "$s"
$g tables build --model "$s"/model_0*.pgm --x -5:5:11 --y -5:5:11 --theta -1.5:1.5:7 -o "$out/scene.gbt"
init=$(sed -n 2p "$s/gt.csv" | cut -d, -f2-5)
$g track --table "$out/scene.gbt" --frames "$s/frames.y4m" --init "$init" -o "$out/scene-poses.csv" --stats "$out/scene-stats.json"
$g eval --poses "$out/scene-poses.csv" --gt "$s/gt.csv" > "$out/scene-accuracy.json"
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
def timing(s):
    t = s["per_frame_us"]
    return (f"{t['mean']:.1f} us mean, {t['p50']:.1f} p50, {t['p99']:.1f} p99, {t['max']:.1f} max "
            f"({s['features_per_frame']:.0f} features, {s['votes_per_frame']:.0f} votes, {s['lost_frames']} lost frames); "
            f"table {s['table_bytes']} bytes, {s['cells']} cells")
a = json.load(open(f"{out}/accuracy.json"))
s = json.load(open(f"{out}/stats.json"))
print(f"\nthesis shape, 30% noise: {a['exact']}/{a['frames']} frames on the exact pixel, {a['wrong']} wrong, "
      f"mean error {a['mean_error_px']:.3f} px, max {a['max_error_px']:.3f} px")
print(f"  per frame: {timing(s)}")
a = json.load(open(f"{out}/scene-accuracy.json"))
s = json.load(open(f"{out}/scene-stats.json"))
n = a["frames"]
pct = lambda k: f"{100.0 * a[k] / n:.1f}%"
reacq = ", ".join("never" if r < 0 else f"{r} frames" for r in a["reacquired_after_frames"]) or "no occlusion"
print(f"grayscale 4-DOF scene (cog, gravel, random walk, occluder from the left, 3 depths): over {n} visible frames "
      f"{pct('within_1px')} within 1 px, {pct('within_2px')} within 2 px, {pct('within_1deg')} within 1 deg, "
      f"depth exact {pct('depth_exact')}; reacquired after the occlusion: {reacq}")
print(f"  per frame: {timing(s)}")
print(f"files: {out}/poses.csv {out}/stats.json {out}/accuracy.json {out}/scene-poses.csv {out}/scene-stats.json {out}/scene-accuracy.json")
PY
# The scene suite: gabarit bench runs gabarit-bench, built only with OpenCV (its peer).
if $g bench --help > /dev/null 2>&1; then
  $g bench --suite $suite --no-particles --no-detection --out "$out/suite" 2> "$out/suite.log"
  echo
  echo "scene suite ($out/suite/suite.md):"
  sed -n '/^## Summary/,/^## Per scene/p' "$out/suite/suite.md" | sed '1d;$d'
  echo "files: $out/suite/suite.md $out/suite/suite-scenes.csv"
else
  echo "scene suite: skipped (gabarit bench needs gabarit-bench, built with libopencv-imgproc-dev)"
fi
