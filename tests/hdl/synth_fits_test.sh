#!/usr/bin/env bash
# The 1-lane voter fits an iCE40 UP5K (yosys + nextpnr place and route) with
#   - the thesis curve's table (121 cells, 1-pixel cells over +-5 px), and
#   - the ~2800-point watch shape's table, built to the voter's reference
#     budget (tables build --max-references 8100: what the block RAM holds)
#     and exported with 3-bit range counts, so that one 16-bit offsets word
#     per ROI pixel (308x208) fills the four SPRAMs.
# Checks the fit; Fmax is reported, never asserted (hdl/synth/synth.sh
# prints it).
# Usage: synth_fits_test.sh PATH/TO/gabarit
set -euo pipefail
g=${1:?usage: synth_fits_test.sh PATH/TO/gabarit}
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0 failed=0
check() {  # NAME TABLE [EXPORT_ARGS]
  GABARIT=$g EXPORT_ARGS=${3:-} SEEDS=1 "$here/../../hdl/synth/synth.sh" "$2" "$work/$1" 1 > "$work/$1.txt" 2>&1 || true
  grep "^| 1 " "$work/$1.txt" || true
  if grep -q "^| 1 .*| yes |" "$work/$1.txt"; then
    echo "$1: fits"; passed=$((passed + 1))
  else
    echo "$1: the 1-lane voter does not fit the UP5K:"; cat "$work/$1.txt"; failed=$((failed + 1))
  fi
}
"$g" synth --shape curve --frames 1 -o "$work/curve" 2>/dev/null
"$g" tables build --model-points "$work/curve/model.csv" --binary --x -5:5:11 --y -5:5:11 -o "$work/curve.gbt" 2>/dev/null
check curve "$work/curve.gbt"
"$g" synth --shape watch --frames 1 -o "$work/watch" 2>/dev/null
"$g" tables build --model-points "$work/watch/model.csv" --binary --x -5:5:11 --y -5:5:11 --max-references 8100 \
  -o "$work/watch.gbt" 2>/dev/null
check watch "$work/watch.gbt" "--range-count 3"
echo "$passed passed, $failed failed"
[ "$failed" = 0 ]
