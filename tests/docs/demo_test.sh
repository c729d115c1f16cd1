#!/usr/bin/env bash
# tools/scripts/demo.sh, as README.md tells a reader to run it, on the gabarit
# under test (--gabarit: no install, no build): it must exit 0 and print both
# summaries with figures in them, and leave the files it lists.
# Usage: demo_test.sh SOURCE_DIR GABARIT
set -euo pipefail
src=${1:?usage: demo_test.sh SOURCE_DIR GABARIT}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bash "$src/tools/scripts/demo.sh" --gabarit "${2:?}" --out "$work/demo" > "$work/out" 2> "$work/err" ||
  { tail -20 "$work/err"; echo "FAIL: demo.sh exited non-zero"; exit 1; }
cat "$work/out" | grep -v '^$'
grep -Eq '^thesis shape, 30% noise: [0-9]+/300 frames on the exact pixel' "$work/out" ||
  { echo "FAIL: demo.sh did not print the thesis shape's summary"; exit 1; }
grep -Eq '^grayscale 4-DOF scene .*: over [0-9]+ visible frames [0-9.]+% within 1 px' "$work/out" ||
  { echo "FAIL: demo.sh did not print the 4-DOF scene's summary"; exit 1; }
grep -Eq 'per frame: [0-9.]+ us mean' "$work/out" || { echo "FAIL: demo.sh printed no timing"; exit 1; }
grep -Eq '^\| gabarit default session \| [0-9.]+% ' "$work/out" || { echo "FAIL: demo.sh printed no suite summary"; exit 1; }
for f in $(sed -n 's/^files: //p' "$work/out" | tr ' ' '\n'); do
  [ -s "$f" ] || { echo "FAIL: demo.sh lists $f but did not write it"; exit 1; }
done
bash "$src/tools/scripts/demo.sh" --bogus > /dev/null 2>&1 && { echo "FAIL: demo.sh accepted --bogus"; exit 1; }
echo "PASS: demo.sh ran and printed its summaries"
