#!/usr/bin/env bash
# The 1-lane voter, sized for the thesis curve's table (121 cells, 1-pixel
# cells over +-5 px), synthesises with yosys and places and routes on an
# iCE40 UP5K with nextpnr. Checks that it fits; Fmax is reported, never
# asserted (hdl/synth/synth.sh prints it).
# Usage: synth_fits_test.sh PATH/TO/gabarit
set -euo pipefail
g=${1:?usage: synth_fits_test.sh PATH/TO/gabarit}
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$g" synth --shape curve --frames 1 -o "$work/seq" 2>/dev/null
"$g" tables build --model-points "$work/seq/model.csv" --binary --x -5:5:11 --y -5:5:11 -o "$work/curve.gbt" 2>/dev/null
GABARIT=$g "$here/../../hdl/synth/synth.sh" "$work/curve.gbt" "$work/out" 1 > "$work/report.txt" 2>&1
grep "^| 1 " "$work/report.txt"
if grep -q "^| 1 .*| yes |" "$work/report.txt"; then
  echo "1 passed, 0 failed"
else
  echo "the 1-lane voter does not fit the UP5K:"; cat "$work/report.txt"; echo "0 passed, 1 failed"; exit 1
fi
