#!/usr/bin/env bash
# README.md's "Using the CLI" block, run as a reader would run it: every line
# of the block's first ```sh fence, in order, in an empty folder, with the
# block's own `g=build/release/tools/gabarit` pointed at the gabarit under test.
# Each command must exit 0 and each file the block names with -o must exist.
# Usage: readme_cli.sh SOURCE_DIR GABARIT
set -euo pipefail
src=$(cd "${1:?usage: readme_cli.sh SOURCE_DIR GABARIT}" && pwd)
gabarit=$(cd "$(dirname "${2:?}")" && pwd)/$(basename "$2")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
awk '/^## Using the CLI/{f=1} f&&/^```sh/{p=1;next} p&&/^```/{exit} p' "$src/README.md" > "$work/block.sh"
[ -s "$work/block.sh" ] || { echo "FAIL: README.md has no sh block under 'Using the CLI'"; exit 1; }
grep -qx 'g=build/release/tools/gabarit' "$work/block.sh" || { echo "FAIL: the block no longer starts from g=build/release/tools/gabarit"; exit 1; }
sed -i "s|^g=build/release/tools/gabarit\$|g=$gabarit|" "$work/block.sh"
mkdir "$work/run"
n=0
while IFS= read -r line; do
  case "$line" in ''|'#'*) continue ;; esac
  n=$((n + 1))
  echo "+ $line"
  (cd "$work/run" && g=$gabarit bash -euo pipefail -c "$line") > "$work/out" 2>&1 || {
    tail -20 "$work/out"; echo "FAIL: README.md's CLI block, command $n: $line"; exit 1; }
  for out in $(grep -oE '(-o|--stats|--plots) [^ ]+' <<< "$line" | cut -d' ' -f2); do
    [ -e "$work/run/$out" ] || { echo "FAIL: '$line' did not write $out"; exit 1; }
  done
done < "$work/block.sh"
echo "PASS: README.md's CLI block, $n commands"
