#!/usr/bin/env bash
# Tuning scenes beyond the suite's: 14 tilted focus stacks (3, 5 or 7
# depths) of the suite's objects, backgrounds and motions with seeds the
# suite does not use (200..213), each tracked with `gabarit track`'s
# defaults from its first true pose, with the suite's table (x, y -5..5 px
# in 1-px cells, theta -1.5..1.5 deg in 0.5-deg cells, every depth).
# Prints per scene and on the mean: within 1 px, within 1 degree and depth
# exact over the visible frames, and the mean us per frame.
# docs/tracking.md ("Vote, then verify") reports what changes measured here.
#
# Usage: extra-scenes.sh GABARIT OUT_DIR
#   GABARIT  the gabarit binary to run
#   OUT_DIR  scenes and tables are made there once and reused; each run's
#            poses are written as OUT_DIR/NN/poses.csv
set -euo pipefail

if [[ $# -ne 2 ]]; then
  echo "usage: $0 GABARIT OUT_DIR" >&2
  exit 2
fi
gabarit=$1
out=$2
mkdir -p "$out"

# object background motion depths, one scene each.
scenes=(
  "cog gravel smooth 3" "coin grass walk 5" "cat page sweep 7" "astronaut brick spin 3"
  "cup moon stopgo 5" "horse smooth walk 7" "pipette grass sweep 3" "large page smooth 5"
  "cog moon walk 7" "coin page sweep 3" "cat smooth smooth 5" "cup grass sweep 7"
  "astronaut gravel walk 5" "horse page stopgo 3"
)

for i in "${!scenes[@]}"; do
  read -r object background motion depths <<<"${scenes[$i]}"
  dir=$(printf '%s/%02d' "$out" "$i")
  if [[ ! -f $dir/gt.csv ]]; then
    "$gabarit" synth --scene "$object" --background "$background" --motion "$motion" --depths "$depths" \
      --frames 160 --seed $((200 + i)) -o "$dir" >/dev/null 2>"$out/log" || { cat "$out/log" >&2; exit 1; }
  fi
  if [[ ! -f $dir/table.gbt ]]; then
    models=()
    for m in "$dir"/model_*.pgm; do models+=(--model "$m"); done
    "$gabarit" tables build "${models[@]}" --x -5:5:11 --y -5:5:11 --theta -1.5:1.5:7 -o "$dir/table.gbt" \
      >/dev/null 2>"$out/log" || { cat "$out/log" >&2; exit 1; }
  fi
  init=$(awk -F, 'NR == 2 { print $2 "," $3 "," $4 "," $5 }' "$dir/gt.csv")
  summary=$("$gabarit" track --table "$dir/table.gbt" --frames "$dir/frames.y4m" --init "$init" -o "$dir/poses.csv" 2>&1 |
    grep -o '[0-9.]* us/frame mean' || true)
  # Join the truth and the poses by row (both have one row per frame).
  paste -d, "$dir/gt.csv" "$dir/poses.csv" | awk -F, -v name="$(printf '%02d %s' "$i" "${scenes[$i]}")" -v us="${summary%% *}" '
    NR > 1 && $6 == 1 {
      n++
      dx = $8 - $2; dy = $9 - $3; dt = $10 - $4
      if (dx * dx + dy * dy <= 1) px++
      if (dt <= 1 && dt >= -1) deg++
      if ($11 == $5) depth++
    }
    END { printf "%-32s within 1 px %5.1f  within 1 deg %5.1f  depth exact %5.1f  us/frame %s\n", name, 100 * px / n, 100 * deg / n, 100 * depth / n, us }'
done | awk '{ print; px += $9; deg += $13; depth += $16; n++ }
  END { printf "%-32s within 1 px %5.1f  within 1 deg %5.1f  depth exact %5.1f\n", "mean", px / n, deg / n, depth / n }'
