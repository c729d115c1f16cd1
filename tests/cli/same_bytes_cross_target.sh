#!/usr/bin/env bash
# The particle filter, detection and orientation-channel tables give the
# same bytes on this target as on the host: the host's gabarit makes a scene
# and tables and tracks or detects; this target's gabarit (under its
# emulator) runs the same commands on the same frames.
#   same_bytes_cross_target.sh HOST_GABARIT TARGET_COMMAND...
set -euo pipefail
host=$1; shift
[ -x "$host" ] || { echo "same_bytes_cross_target: the host's gabarit ($host) is missing: build the release preset first" >&2; exit 1; }
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
"$host" synth --scene microscope --frames 30 --depths 2 --occlusion 12:5 --seed 4 -o "$work/s" 2>/dev/null || fail "synth"
"$host" tables build --model "$work/s/model_00.pgm" --model "$work/s/model_01.pgm" --x -4:4:9 --y -4:4:9 --theta -1.5:1.5:7 \
  -o "$work/t.gbt" 2>/dev/null || fail "tables build"
"$host" tables build --model "$work/s/model_00.pgm" --model "$work/s/model_01.pgm" --x -4:4:9 --y -4:4:9 --theta -1.5:1.5:7 \
  --orientation-channels 8 -o "$work/t8.gbt" 2>/dev/null || fail "tables build --orientation-channels 8"
init=$(sed -n 2p "$work/s/gt.csv" | cut -d, -f2-5)
# Detection in every frame.
"$host" detect --table "$work/t.gbt" "$work/s/frames.y4m" -o "$work/host.csv" 2>/dev/null || fail "host: detect"
"$@" detect --table "$work/t.gbt" "$work/s/frames.y4m" -o "$work/target.csv" 2>/dev/null || fail "target: detect"
cmp "$work/host.csv" "$work/target.csv" || fail "detect: the target's detections differ from the host's"
echo "same bytes: detect ($(($(wc -l < "$work/host.csv") - 1)) detections)"
# An orientation-channel table tracked.
"$host" track --table "$work/t8.gbt" --frames "$work/s/frames.y4m" --init "$init" -o "$work/host.csv" 2>/dev/null || fail "host: track t8"
"$@" track --table "$work/t8.gbt" --frames "$work/s/frames.y4m" --init "$init" -o "$work/target.csv" 2>/dev/null || fail "target: track t8"
cmp "$work/host.csv" "$work/target.csv" || fail "track (orientation channels): the target's poses differ from the host's"
echo "same bytes: track with 8 orientation channels"
for variant in "--tracker particle" "--tracker particle --measure stencil --seed 9" "--tracker particle --without all --particles 300" \
               "--recovery particle" "--recovery detect"; do
  # shellcheck disable=SC2086
  "$host" track $variant --table "$work/t.gbt" --frames "$work/s/frames.y4m" --init "$init" -o "$work/host.csv" 2>/dev/null \
    || fail "host: track $variant"
  # shellcheck disable=SC2086
  "$@" track $variant --table "$work/t.gbt" --frames "$work/s/frames.y4m" --init "$init" -o "$work/target.csv" 2>/dev/null \
    || fail "target: track $variant"
  cmp "$work/host.csv" "$work/target.csv" || fail "track $variant: the target's poses differ from the host's"
  echo "same bytes: track $variant ($(($(wc -l < "$work/host.csv") - 1)) frames)"
done
