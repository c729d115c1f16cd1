#!/usr/bin/env bash
# make_corpora.sh GABARIT MAKE_TABLE_SEEDS OUTDIR MAKE_LINK_SEEDS: seed
# corpora for every fuzz target, made by the project's own tools (nothing
# committed): tables (make_table_seeds: valid ones and one per loader error),
# Y4M and PGM from `gabarit synth`, points and pose CSVs from synth, track and
# by hand, HIL link streams (make_link_seeds), test vectors from `gabarit vectors`.
set -euo pipefail
g=${1:?usage: make_corpora.sh GABARIT MAKE_TABLE_SEEDS OUTDIR}
seeds=${2:?}
out=${3:?}
link_seeds=${4:?}
rm -rf "$out"
mkdir -p "$out"/{table,y4m,pgm,points_csv,pose_csv,link,board_map,session_profile,vectors}
"$link_seeds" "$out/link"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$seeds" "$out/table" > /dev/null
"$g" synth --shape random --points 40 --frames 3 --size 24x20 --noise 0.1 --seed 2 -o "$work/bin" 2> /dev/null
"$g" tables build --model-points "$work/bin/model.csv" --binary --x -2:2:5 --y -2:2:5 -o "$work/bin.gbt" 2> /dev/null
"$g" track --table "$work/bin.gbt" --frames "$work/bin/frames.y4m" --init 12,10 -o "$work/poses.csv" 2> /dev/null
cp "$work/bin/frames.y4m" "$out/y4m/mono.y4m"
cp "$work/bin/model.pgm" "$out/pgm/p5.pgm"
cp "$work/bin/model.csv" "$out/points_csv/model.csv"
cp "$work/bin/gt.csv" "$out/pose_csv/gt.csv"
cp "$work/poses.csv" "$out/pose_csv/poses.csv"
# Small hand-made seeds: 4:2:0 and 4:4:4 streams, an ASCII PGM with a
# comment and maxval 15, headers the readers refuse, CSV edge cases.
{ printf 'YUV4MPEG2 W4 H2 F30:1 C420jpeg\nFRAME\n'; head -c 12 /dev/zero; printf 'FRAME\n'; head -c 12 /dev/zero; } > "$out/y4m/c420.y4m"
{ printf 'YUV4MPEG2 W2 H2 C444 XEXT=1\nFRAME\n'; head -c 12 /dev/zero; } > "$out/y4m/c444.y4m"
printf 'YUV4MPEG2 W2 H2 C420p10\nFRAME\n' > "$out/y4m/p10.y4m"
printf 'YUV4MPEG2 W2 W2 H2\r\n' > "$out/y4m/twice-crlf.y4m"
printf 'P2\n# a comment\n3 2\n15\n0 1 2\n3 4 15\n' > "$out/pgm/p2.pgm"
{ printf 'P5 2 2 255 # after\n'; head -c 4 /dev/zero; } > "$out/pgm/comment-after-maxval.pgm"
printf 'x,y\n0,0\n1,-1\n# comment\n\n16384,-16384\n' > "$out/points_csv/edges.csv"
printf '10;20\n' > "$out/points_csv/semicolon.csv"
printf 'frame,x,y,theta_deg,depth,visible\n0,1.5,2,0,0,1\n1,nan,2,0,0,0\n4294967296,1,1,0,0,1\n' > "$out/pose_csv/bad.csv"
cp "$(dirname "$0")"/../../hil/boards/*.yaml "$out/board_map/"
printf 'name: b\nrelay: x\ngpio:\n  lock: 99999\n' > "$out/board_map/bad-line.yaml"
# Session profiles: every key (gabarit track --save-profile), a short one, refusals.
"$g" track --table "$work/bin.gbt" --frames "$work/bin/frames.y4m" --init 12,10 --recovery detect --detect-after 3 \
    --save-profile "$out/session_profile/detect.profile" -o "$work/p2.csv" 2> /dev/null
printf 'gabarit-session-profile 1\n# tuned\nplain = true\nrecover = true\nsearch-budget = 40\n' > "$out/session_profile/short.profile"
printf 'gabarit-session-profile 1\nplain = true\nrecovery = particle\n' > "$out/session_profile/needs-recovery.profile"
printf 'gabarit-session-profile 1\nwithout = modes,all\nseed = 18446744073709551615\n' > "$out/session_profile/bad-seed.profile"
printf 'gabarit-session-profile 1\ntracker = particle\nmeasure = edges\nparticles = 300\n' > "$out/session_profile/particle.profile"
# Test vectors: a small set from `gabarit vectors` (one frame, two session
# frames, ten particles), and a truncated one.
"$g" vectors --out "$work/vec" --points 100 --depths 1 --frames 1 --session-frames 2 --hidden 1,1 --particles 10 \
    --table-bytes 8192 2> /dev/null
cp "$work/vec/vectors.gbv" "$work/vec/session.gbs" "$work/vec/particle.gbp" "$work/vec/particle-intensity.gbp" "$out/vectors/"
head -c 100 "$work/vec/particle.gbp" > "$out/vectors/truncated.gbp"
echo "make_corpora: $(find "$out" -type f | wc -l) seeds in $out"
