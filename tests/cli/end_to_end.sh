#!/usr/bin/env bash
# End-to-end test of the gabarit CLI: synth -> tables build -> track -> eval
# on the issue's acceptance scenario, plus the CLI's error behaviour.
# Usage: end_to_end.sh PATH/TO/gabarit
set -euo pipefail
g=${1:?usage: end_to_end.sh PATH/TO/gabarit}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# Expect exit code $1 from the rest of the command line, and stderr matching $2.
expect() {
  local want=$1 pattern=$2; shift 2
  local rc=0
  "$@" >"$work/out" 2>"$work/err" || rc=$?
  [ "$rc" = "$want" ] || fail "'$*' exited $rc, want $want: $(cat "$work/err")"
  grep -q -- "$pattern" "$work/err" || fail "'$*' stderr lacks '$pattern': $(cat "$work/err")"
}

# Help everywhere, exit 0. (Into a file first: grep -q closing the pipe
# early would fail a long help's write under pipefail.)
for cmd in "tables build" "tables inspect" "tables analyse" synth detect track eval vectors; do
  $g $cmd --help > "$work/help.txt" || fail "$cmd --help exited non-zero"
  grep -q "^usage: gabarit $cmd" "$work/help.txt" || fail "$cmd --help"
done
$g --help > "$work/help.txt" && grep -q "tables analyse" "$work/help.txt" || fail "gabarit --help"

# The acceptance scenario at 0% and 30% noise.
for noise in 0 0.3; do
  d="$work/seq$noise"
  $g synth --shape random --points 200 --frames 120 --max-step 4 --noise $noise --seed 5 -o "$d" 2>/dev/null
  head -1 "$d/gt.csv" | grep -qx "frame,x,y,theta_deg,depth,visible" || fail "gt.csv header"
  $g tables build --model "$d/model.pgm" --binary --x -5:5:11 --y -5:5:11 -o "$d/t.gbt" 2>/dev/null
  init=$(sed -n 2p "$d/gt.csv" | cut -d, -f2,3)
  $g track --table "$d/t.gbt" --frames "$d/frames.y4m" --init "$init" -o "$d/poses.csv" --stats "$d/stats.json" 2>/dev/null
  head -1 "$d/poses.csv" | grep -qx "frame,x,y,theta_deg,depth,votes,score,status" || fail "poses.csv header"
  [ "$(wc -l < "$d/poses.csv")" = 121 ] || fail "poses.csv rows"
  for key in frames per_frame_us mean p50 p99 max; do grep -q "\"$key\"" "$d/stats.json" || fail "stats.json lacks $key"; done
  # The frame-cost ledger: JSON, every phase, the votes it counts are the run's.
  python3 - "$d/stats.json" <<'PY' || fail "stats.json's ledger: $(cat "$d/stats.json")"
import json, sys
s = json.load(open(sys.argv[1]))
l = s["ledger"]
phases = ["features", "vote", "verify", "depth", "recovery", "survey", "other"]
assert all(l[p]["us_per_frame"] >= 0 and l[p]["work_per_frame"] >= 0 for p in phases), l
assert l["features"]["us_per_frame"] > 0 and l["vote"]["us_per_frame"] > 0, l
assert sum(l[p]["us_per_frame"] for p in phases) <= s["per_frame_us"]["mean"] * 1.01 + 0.01, (l, s["per_frame_us"])
assert l["votes_per_frame"] >= s["votes_per_frame"] and l["vote"]["work_per_frame"] == l["votes_per_frame"], l
assert l["io"]["us_per_frame"] >= 0 and l["pixels_scanned_per_frame"] > 0, l
PY
  $g eval --poses "$d/poses.csv" --gt "$d/gt.csv" --require-exact > "$d/acc.json" || fail "not exact at noise $noise: $(cat "$d/acc.json")"
done

# A directory of PGM frames tracks like the Y4M it came from (and tables are byte-identical per seed).
d="$work/seq0.3"
$g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --keep 0.5 --seed 3 -o "$work/a.gbt" 2>/dev/null
$g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --keep 0.5 --seed 3 -o "$work/b.gbt" 2>/dev/null
cmp -s "$work/a.gbt" "$work/b.gbt" || fail "tables differ for one seed"
$g tables inspect "$work/a.gbt" > "$work/inspect.json"
for key in cells references bytes bytes_per_cell refs_per_pixel_histogram stencil_sizes; do
  grep -q "\"$key\"" "$work/inspect.json" || fail "inspect lacks $key"
done
python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$work/inspect.json" 2>/dev/null || [ $? = 127 ] || fail "inspect output is not JSON"

# A velocity random walk that reverses at the margins, 46% of pixels flipped
# (noise alone scores 0.47 of a stencil, the target 0.54): the default session
# must be exact where the plain loop is (71/100 frames when confidence took no
# account of what clutter scores by chance).
w="$work/walk"
$g synth --shape watch --motion walk --frames 100 --max-step 4 --noise 0.46 --seed 3 -o "$w" 2>/dev/null \
  || fail "synth --shape watch --motion walk"
$g tables build --model-points "$w/model.csv" --binary --x -5:5:11 --y -5:5:11 -o "$w/t.gbt" 2>/dev/null
$g track --plain --table "$w/t.gbt" --frames "$w/frames.y4m" --init "$(sed -n 2p "$w/gt.csv" | cut -d, -f2,3)" -o "$w/pp.csv" 2>/dev/null
$g eval --poses "$w/pp.csv" --gt "$w/gt.csv" --require-exact > /dev/null || fail "the plain loop should be exact on the noisy walk"
winit=$(sed -n 2p "$w/gt.csv" | cut -d, -f2,3)
$g track --table "$w/t.gbt" --frames "$w/frames.y4m" --init "$winit" -o "$w/p.csv" 2>/dev/null || fail "track the walk"
$g eval --poses "$w/p.csv" --gt "$w/gt.csv" --require-exact > "$w/acc.json" || fail "the default session is not exact on the walk: $(cat "$w/acc.json")"
expect 2 "want steps or walk" $g synth --shape random --motion spin --frames 2 -o "$w/x"

# Voting on several threads (the plain loop) gives the same poses as one thread.
init0=$(sed -n 2p "$d/gt.csv" | cut -d, -f2,3)
$g track --table "$work/a.gbt" --frames "$d/frames.y4m" --init "$init0" --plain --voter csr -o "$work/one.csv" 2>/dev/null || fail "track (1 thread)"
$g track --table "$work/a.gbt" --frames "$d/frames.y4m" --init "$init0" --threads 3 -o "$work/three.csv" 2>/dev/null || fail "track --threads 3"
cmp -s "$work/one.csv" "$work/three.csv" || fail "--threads 3 changed the poses"
expect 2 "plain loop" $g track --table "$work/a.gbt" --frames "$d/frames.y4m" --init "$init0" --threads 2 --motion-filter

# A focus stack given as --model a b (two depths) builds one cell set per depth.
$g tables build --model "$d/model.pgm" "$d/model.pgm" --binary --x -1:1:3 --y 0:0:1 -o "$work/stack.gbt" 2>/dev/null
grep -q '"depths": 2' <($g tables inspect "$work/stack.gbt") || fail "two --model images did not make two depths"
expect 2 "unexpected argument" $g tables build --model-points "$d/model.csv" stray.pgm --binary --x 0:0:1 --y 0:0:1 -o "$work/x.gbt"

# Errors: usage errors exit 2, bad input exits 1, each naming the problem.
expect 2 "unknown command" $g frobnicate
expect 2 "missing required option --out" $g vectors --frames 2
expect 2 "--depths" $g vectors --out "$work/v" --depths 0
expect 2 "missing required option --x" $g tables build --model-points "$d/model.csv" --binary --y 0:0:1 -o "$work/x.gbt"
expect 2 "want MIN:MAX:CELLS" $g tables build --model-points "$d/model.csv" --binary --x 5 --y 0:0:1 -o "$work/x.gbt"
expect 2 "one cell needs MIN == MAX" $g tables build --model-points "$d/model.csv" --binary --x 0:3:1 --y 0:0:1 -o "$work/x.gbt"
expect 2 "keep" $g tables build --model-points "$d/model.csv" --binary --x 0:0:1 --y 0:0:1 --keep 1.5 -o "$work/x.gbt"
expect 2 "--binary or --threshold" $g tables build --model-points "$d/model.csv" --x 0:0:1 --y 0:0:1 -o "$work/x.gbt"
expect 1 "cannot open" $g tables build --model "$work/missing.pgm" --x 0:0:1 --y 0:0:1 -o "$work/x.gbt"
printf 'P5\n4 4\n255\nabc' > "$work/short.pgm"
expect 1 "truncated PGM" $g tables build --model "$work/short.pgm" --binary --x 0:0:1 --y 0:0:1 -o "$work/x.gbt"
printf 'x,y\n1,2\n3,oops\n' > "$work/bad.csv"
expect 1 "bad.csv:3" $g tables build --model-points "$work/bad.csv" --binary --x 0:0:1 --y 0:0:1 -o "$work/x.gbt"
head -c 1000 "$work/a.gbt" > "$work/trunc.gbt"
expect 1 "truncated" $g tables inspect "$work/trunc.gbt"
cp "$work/a.gbt" "$work/flip.gbt"
printf '\xff' | dd of="$work/flip.gbt" bs=1 seek=300 conv=notrunc 2>/dev/null
expect 1 "bad-checksum" $g track --table "$work/flip.gbt" --frames "$d/frames.y4m" --init 1,1
expect 1 "not a gabarit\|bad-magic" $g tables inspect "$d/gt.csv"
expect 2 "--init" $g track --table "$work/a.gbt" --frames "$d/frames.y4m" --init 1
expect 1 "not a Y4M" $g track --table "$work/a.gbt" --frames "$d/gt.csv" --init 1,1
printf 'YUV4MPEG2 W8 H8 C422\nFRAME\n' > "$work/c422.y4m"
expect 1 "C422 not supported" $g track --table "$work/a.gbt" --frames "$work/c422.y4m" --init 1,1
printf 'YUV4MPEG2 W8 H8 Cmono\nFRAME\nabc' > "$work/cut.y4m"
expect 1 "frame 0: truncated" $g track --table "$work/a.gbt" --frames "$work/cut.y4m" --init 1,1
# The grayscale 4-DOF scene end to end: model stack, table, filtered tracking.
s="$work/scene"
$g synth --scene microscope --frames 40 --depths 2 --occlusion 15:6 -o "$s" 2>/dev/null || fail "synth --scene"
[ -f "$s/model_00.pgm" ] && [ -f "$s/model_01.pgm" ] || fail "synth --scene: model stack missing"
$g tables build --model "$s/model_00.pgm" --model "$s/model_01.pgm" --x -4:4:9 --y -4:4:9 --theta -1.5:1.5:7 \
  -o "$s/t.gbt" 2>/dev/null || fail "tables build from the scene's model stack"
$g tables inspect "$s/t.gbt" > "$s/t.json" && grep -q '"depths": 2' "$s/t.json" || fail "scene table depths"
init=$(sed -n 2p "$s/gt.csv" | cut -d, -f2-5)
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --motion-filter --refine --recover -o "$s/p.csv" 2>/dev/null \
  || fail "track --motion-filter --refine --recover"
$g eval --gt "$s/gt.csv" --poses "$s/p.csv" > "$s/acc.json" || fail "eval on the scene"
grep -q '"frames": 34' "$s/acc.json" || fail "scene: 34 visible frames expected: $(cat "$s/acc.json")"
grep -q '"reacquired_after_frames": \[[0-9]' "$s/acc.json" || fail "scene: not reacquired after the occlusion: $(cat "$s/acc.json")"
# Depth by intensity: the scene's two depths, every visible frame's depth exact.
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --motion-filter --refine --recover \
  --focus-stack "$s/model_00.pgm,$s/model_01.pgm" -o "$s/pf.csv" 2>/dev/null || fail "track --focus-stack"
$g eval --gt "$s/gt.csv" --poses "$s/pf.csv" > "$s/accf.json" || fail "eval with --focus-stack"
grep -q '"depth_exact": 34' "$s/accf.json" || fail "--focus-stack: every visible depth expected exact: $(cat "$s/accf.json")"
# By default the session uses the focus stack the table carries: the same
# poses as naming its images; --no-focus-stack and --no-model-images go without.
grep -q '"images_stored": true' "$s/t.json" || fail "a table built from images should carry them: $(cat "$s/t.json")"
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/pd.csv" 2>/dev/null || fail "track (defaults)"
cmp -s "$s/pf.csv" "$s/pd.csv" || fail "the default session with the table's images differs from --focus-stack with the same images"
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --no-focus-stack -o "$s/pn.csv" 2>/dev/null || fail "--no-focus-stack"
cmp -s "$s/p.csv" "$s/pd.csv" || fail "--motion-filter --refine --recover are the defaults and should change nothing"
$g tables build --model "$s/model_00.pgm" --model "$s/model_01.pgm" --x -4:4:9 --y -4:4:9 --theta -1.5:1.5:7 --no-model-images \
  -o "$s/t10.gbt" 2>/dev/null || fail "tables build --no-model-images"
$g tables inspect "$s/t10.gbt" > "$s/t10.json" && grep -q '"images_stored": false' "$s/t10.json" || fail "--no-model-images stored images"
[ "$(stat -c %s "$s/t10.gbt")" -lt "$(stat -c %s "$s/t.gbt")" ] || fail "--no-model-images: not smaller"
$g track --table "$s/t10.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/p10.csv" 2>/dev/null || fail "track a 1.0 table"
cmp -s "$s/pn.csv" "$s/p10.csv" || fail "a table without images should track as --no-focus-stack"
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --plain -o "$s/pp.csv" 2>/dev/null || fail "track --plain"
# The particle filter (docs/particle-filter.md): it tracks the scene, the
# same seed gives the same bytes, another seed others; options are checked.
$g track --tracker particle --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/pa.csv" 2>/dev/null || fail "track --tracker particle"
$g track --tracker particle --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/pb.csv" 2>/dev/null || fail "track --tracker particle (again)"
cmp -s "$s/pa.csv" "$s/pb.csv" || fail "the particle filter: the same seed gave different poses"
$g track --tracker particle --seed 2 --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/pc.csv" 2>/dev/null || fail "--seed 2"
cmp -s "$s/pa.csv" "$s/pc.csv" && fail "the particle filter: another seed gave the same poses"
[ "$(wc -l < "$s/pa.csv")" = 41 ] || fail "the particle filter: one row per frame expected"
# Its default measure is the verified score where the table has model
# images; the edge measure stays an option, and the default without images.
$g track --tracker particle --measure edges --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/pe.csv" 2>/dev/null \
  || fail "track --tracker particle --measure edges"
cmp -s "$s/pa.csv" "$s/pe.csv" && fail "the particle filter: --measure edges gave the default's poses (the intensity measure's)"
# Both hold the microscope scene: the edge measure within 2 px on 80% of
# its frames, the intensity measure (its likelihood broader, its mean less
# sharp on this small scene) within 5 px on every one.
$g eval --gt "$s/gt.csv" --poses "$s/pe.csv" > "$s/acc_pe.json" || fail "eval the particle filter (edges)"
$g eval --gt "$s/gt.csv" --poses "$s/pa.csv" > "$s/acc_pf.json" || fail "eval the particle filter"
python3 - "$s/acc_pe.json" "$s/acc_pf.json" <<'PY' || fail "the particle filter lost the microscope scene: $(cat "$s/acc_pe.json" "$s/acc_pf.json")"
import json, sys
e, i = (json.load(open(p)) for p in sys.argv[1:3])
sys.exit(0 if e["within_2px"] >= 0.8 * e["frames"] and i["within_5px"] == i["frames"] else 1)
PY
$g track --tracker particle --measure intensity --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/pi.csv" 2>/dev/null \
  || fail "track --tracker particle --measure intensity"
cmp -s "$s/pa.csv" "$s/pi.csv" || fail "the particle filter: the default measure is not the intensity measure on a table with images"
# Vote-guided proposals are on by default; --without proposals is the filter
# without them, and holds the scene as well (within 5 px on every frame).
$g track --tracker particle --without proposals --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/pu.csv" 2>/dev/null \
  || fail "track --tracker particle --without proposals"
cmp -s "$s/pa.csv" "$s/pu.csv" && fail "the particle filter: --without proposals gave the default's poses"
# Its frame-cost ledger (--stats): the proposals' vote, the measure, the rest.
$g track --tracker particle --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --stats "$s/pstats.json" -o "$s/pa2.csv" 2>/dev/null \
  || fail "track --tracker particle --stats"
# The summary's features and votes are the proposals' vote, and frame reading is timed.
python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); l=j["ledger"]; sys.exit(not (l["vote"]["work_per_frame"] > 0 and l["verify"]["us_per_frame"] > 0 and l["correlations_per_frame"] >= 1000 and j["features_per_frame"] == l["features_per_frame"] > 0 and j["votes_per_frame"] == l["votes_per_frame"] > 0 and l["io"]["us_per_frame"] > 0))' \
  "$s/pstats.json" || fail "the particle filter's ledger: $(cat "$s/pstats.json")"
$g eval --gt "$s/gt.csv" --poses "$s/pu.csv" | python3 -c 'import json,sys; a=json.load(sys.stdin); sys.exit(a["within_5px"] != a["frames"])' \
  || fail "the particle filter without proposals lost the microscope scene"
# The thesis's clustering as issue 31 reads it (running means, light
# particles start no mode) is an option, and holds the scene too.
$g track --tracker particle --mode-clustering running-mean --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/pm.csv" \
  2>/dev/null || fail "track --tracker particle --mode-clustering running-mean"
cmp -s "$s/pa.csv" "$s/pm.csv" && fail "the particle filter: --mode-clustering running-mean gave the default's poses"
$g eval --gt "$s/gt.csv" --poses "$s/pm.csv" | python3 -c 'import json,sys; a=json.load(sys.stdin); sys.exit(a["within_5px"] != a["frames"])' \
  || fail "the particle filter with running-mean modes lost the microscope scene"
expect 2 "want seed or running-mean" $g track --tracker particle --mode-clustering kmeans --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
expect 2 "applies to --tracker particle" $g track --mode-clustering seed --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
$g track --tracker particle --table "$s/t10.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/p10e.csv" 2>/dev/null \
  || fail "track --tracker particle on a table without images"
$g track --tracker particle --measure edges --table "$s/t10.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/p10f.csv" 2>/dev/null \
  || fail "track --tracker particle --measure edges on a table without images"
cmp -s "$s/p10e.csv" "$s/p10f.csv" || fail "the particle filter: without images the default measure is not the edge measure"
expect 1 "needs a table with model images" $g track --tracker particle --measure intensity --table "$s/t10.gbt" --frames "$s/frames.y4m" --init "$init"
$g track --tracker particle --measure stencil --without all --particles 200 --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" \
  -o "$s/ps.csv" 2>/dev/null || fail "track --tracker particle --measure stencil --without all"
$g track --recovery particle --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/pr.csv" 2>/dev/null || fail "track --recovery particle"
$g eval --gt "$s/gt.csv" --poses "$s/pr.csv" > "$s/acc_pr.json" || fail "eval --recovery particle"
grep -q '"reacquired_after_frames": \[[0-9]' "$s/acc_pr.json" || fail "--recovery particle: not reacquired after the occlusion: $(cat "$s/acc_pr.json")"
expect 2 "needs recovery" $g track --recovery particle --plain --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
expect 2 "want auto, grid, detect or particle" $g track --recovery kalman --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
# Detection (docs/detection.md): the model found anywhere with no pose, in
# every frame; tracking without --init; re-acquisition by detection.
$g detect --table "$s/t.gbt" "$s/frames.y4m" -o "$s/det.csv" 2>/dev/null || fail "detect"
head -1 "$s/det.csv" | grep -qx "frame,rank,x,y,theta_deg,depth,score,coarse_score,vote_score" || fail "detect: header"
python3 - "$s/det.csv" "$s/gt.csv" <<'PY' || fail "detect: the target not found in the visible frames"
import csv, math, sys
det = {}
for r in csv.DictReader(open(sys.argv[1])):
    if r["rank"] == "0": det[int(r["frame"])] = r
hits = visible = 0
for g in csv.DictReader(open(sys.argv[2])):
    if g["visible"] != "1": continue
    visible += 1
    d = det.get(int(g["frame"]))
    hits += d is not None and math.hypot(float(d["x"]) - float(g["x"]), float(d["y"]) - float(g["y"])) <= 2
sys.exit(0 if hits >= 0.9 * visible else 1)
PY
$g detect --table "$s/t.gbt" "$s/frames.y4m" -o "$s/det2.csv" 2>/dev/null && cmp -s "$s/det.csv" "$s/det2.csv" || fail "detect: not the same bytes twice"
$g detect --table "$s/t.gbt" "$s/model_00.pgm" --max-count 1 > "$s/det_pgm.csv" 2>/dev/null || fail "detect a PGM"
[ "$(wc -l < "$s/det_pgm.csv")" -le 2 ] || fail "detect --max-count 1: more than one row"
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" -o "$s/pni.csv" 2>/dev/null || fail "track without --init"
$g eval --gt "$s/gt.csv" --poses "$s/pni.csv" > "$s/acc_ni.json" || fail "eval track without --init"
python3 - "$s/acc_ni.json" <<'PY' || fail "track without --init lost the scene: $(cat "$s/acc_ni.json")"
import json, sys
a = json.load(open(sys.argv[1]))
sys.exit(0 if a["within_2px"] >= 0.8 * a["frames"] else 1)
PY
$g track --recovery detect --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" -o "$s/prd.csv" 2>/dev/null || fail "track --recovery detect"
$g eval --gt "$s/gt.csv" --poses "$s/prd.csv" > "$s/acc_prd.json" || fail "eval --recovery detect"
grep -q '"reacquired_after_frames": \[[0-9]' "$s/acc_prd.json" || fail "--recovery detect: not reacquired after the occlusion: $(cat "$s/acc_prd.json")"
expect 2 "want one IMAGE" $g detect --table "$s/t.gbt"
expect 2 "want A <= B" $g detect --table "$s/t.gbt" --theta-range 5:1 "$s/model_00.pgm"
expect 2 "--min-score" $g detect --table "$s/t.gbt" --min-score 2 "$s/model_00.pgm"
expect 2 "at least --max-count" $g detect --table "$s/t.gbt" --max-count 9 --candidates 3 "$s/model_00.pgm"
expect 2 "apply to detection" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --recovery grid --min-score 0.4
expect 2 "needs --init" $g track --tracker particle --table "$s/t.gbt" --frames "$s/frames.y4m"
expect 1 "cannot open" $g detect --table "$s/t.gbt" "$s/missing.pgm"
$g synth --pipette-suite --scenes 1 --frames 3 -o "$work/pipettes" 2>/dev/null || fail "synth --pipette-suite"
grep -q "^0,glass-pipette-gravel-smooth-cover-d1-s1001,tuning," "$work/pipettes/suite.csv" || fail "synth --pipette-suite: listing"
expect 2 "want an integer in \[1, 8\]" $g synth --pipette-suite --scenes 9 -o "$work/pipettes9"
expect 2 "applies to --tracker particle and --recovery particle" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --particles 10
expect 2 "applies to --tracker particle" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --measure edges
expect 2 "not --tracker particle" $g track --tracker particle --plain --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
expect 2 "want stencil or particle" $g track --tracker kalman --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
expect 2 "want auto, intensity, edges or stencil" $g track --tracker particle --measure votes --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
expect 2 "is none of" $g track --tracker particle --without speed --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
expect 2 "--particles" $g track --tracker particle --particles 0 --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
expect 1 "the focus stack has 1 images; the table has 2 depths" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" \
  --motion-filter --focus-stack "$s/model_00.pgm"
expect 2 "applies to the plain loop" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --threads 2 \
  --focus-stack "$s/model_00.pgm,$s/model_01.pgm"
# The cheaper recovery (a search every 2nd lost frame, every 3rd feature screening) still reacquires.
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --motion-filter --refine --recover \
  --search-interval 2 --screen-stride 3 -o "$s/pc.csv" 2>/dev/null || fail "track --search-interval --screen-stride"
$g eval --gt "$s/gt.csv" --poses "$s/pc.csv" > "$s/accc.json" || fail "eval with --search-interval"
grep -q '"reacquired_after_frames": \[[0-9]' "$s/accc.json" || fail "--search-interval 2: not reacquired: $(cat "$s/accc.json")"
expect 2 "--search-interval" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --recover --search-interval 0
expect 2 "--screen-stride" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --recover --screen-stride 17
expect 2 "--search-budget" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --recover --search-budget 559
# The session profile: --save-profile writes what the options describe, and
# --profile reads it back to the same poses; a bad file names its line.
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --recovery detect --search-interval 2 \
  --save-profile "$s/run.profile" -o "$s/pp1.csv" 2>/dev/null || fail "track --save-profile"
grep -qx "gabarit-session-profile 1" <(head -1 "$s/run.profile") || fail "--save-profile: no header: $(cat "$s/run.profile")"
grep -qx "recovery = detect" "$s/run.profile" && grep -qx "search-interval = 2" "$s/run.profile" || fail "--save-profile: $(cat "$s/run.profile")"
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --profile "$s/run.profile" -o "$s/pp2.csv" 2>/dev/null \
  || fail "track --profile"
cmp -s "$s/pp1.csv" "$s/pp2.csv" || fail "--profile of a saved profile does not give the same poses"
printf 'gabarit-session-profile 1\nrecovery = sideways\n' > "$s/bad.profile"
expect 1 "bad.profile:2: recovery 'sideways'" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --profile "$s/bad.profile"
expect 2 "is also an input" $g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --profile "$s/run.profile" \
  --save-profile "$s/run.profile"
# The particle tracker is a choice of the profile: saved, read back to the
# same poses, and run by the HIL's in-process device against its reference.
$g track --tracker particle --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --save-profile "$s/pf.profile" \
  -o "$s/pf1.csv" 2>/dev/null || fail "track --tracker particle --save-profile"
grep -qx "tracker = particle" "$s/pf.profile" || fail "--save-profile: no particle tracker: $(cat "$s/pf.profile")"
cmp -s "$s/pa.csv" "$s/pf1.csv" || fail "--save-profile changed the particle tracker's poses"
$g track --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init" --profile "$s/pf.profile" -o "$s/pf2.csv" 2>/dev/null \
  || fail "track --profile (particle tracker)"
cmp -s "$s/pa.csv" "$s/pf2.csv" || fail "--profile of a saved particle profile does not give --tracker particle's poses"
$g hil run --dut inprocess --profile "$s/pf.profile" --sequence "$s" --table "$s/t.gbt" --frames 12 --report "$s/pf-hil" 2>/dev/null \
  || fail "hil run --profile (particle tracker)"
grep -q '"poses_matching_reference": 12' "$s/pf-hil/summary.json" || fail "hil run, particle tracker: $(head -c 400 "$s/pf-hil/summary.json")"
# The LAVA job writer and replayer (docs/hil-farm.md): a board of its own
# takes no firmware, a QEMU board wants one; a used folder, a replay with no
# link or with two, or a missing hardware map is refused.
expect 2 "takes no --firmware" $g hil lava-job --sequence "$s" --table "$s/t.gbt" --device-type gabarit-board --firmware "$g" --out "$work/lava-a"
expect 2 "wants --firmware" $g hil lava-job --sequence "$s" --table "$s/t.gbt" --out "$work/lava-a"
$g hil lava-job --sequence "$s" --table "$s/t.gbt" --device-type gabarit-board --out "$work/lava-b" > /dev/null || fail "hil lava-job --device-type gabarit-board"
grep -q "method: minimal" "$work/lava-b/job.yaml" && [ ! -e "$work/lava-b/firmware.elf" ] || fail "a gabarit-board job: $(cat "$work/lava-b/job.yaml")"
expect 2 "not an empty folder" $g hil lava-job --sequence "$s" --table "$s/t.gbt" --device-type gabarit-board --out "$work/lava-b"
expect 2 "one of --link" $g hil lava-replay --bundle "$work/lava-b" --foreground
expect 2 "one of --link" $g hil lava-replay --bundle "$work/lava-b" --link 127.0.0.1:1 --board "$work/lava-b/job.yaml" --foreground
expect 2 "no such file" $g hil lava-replay --bundle "$work/lava-b" --board "$work/none.yaml" --foreground
expect 2 "applies to the stencil tracker" $g track --tracker particle --no-verify --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
expect 2 "--measure applies to --tracker particle" $g track --measure edges --table "$s/t.gbt" --frames "$s/frames.y4m" --init "$init"
expect 2 "applies to --scene" $g synth --shape curve --depths 3 -o "$work/x"
expect 2 "one of --shape, --scene, --suite and --pipette-suite" $g synth -o "$work/x"
expect 2 "--light '1.5': want SWING" $g synth --scene cog --light 1.5 -o "$work/x"
expect 2 "--light '0.3:0': want SWING" $g synth --scene cog --light 0.3:0 -o "$work/x"
expect 2 "--sensor-noise and --clean contradict" $g synth --scene cog --clean --sensor-noise 4 -o "$work/x"
expect 2 "--distractor applies to --scene" $g synth --shape curve --distractor -o "$work/x"
$g synth --scene small --distractor --light 0.5:60 --sensor-noise 12 --max-turn 1.2 --motion spin --frames 3 -o "$work/fam" 2> "$work/fam.err" \
  || fail "synth --scene small with the family options"
grep -q "small-gravel-spin-cover-d1-noise12-turn1.2-light0.5:60-twin-s1, 3 frames 640x480" "$work/fam.err" || fail "synth: family options not in the scene's name"
expect 2 "--translations" $g tables build --model "$s/model_00.pgm" --x 0:0:1 --y 0:0:1 --translations middle -o "$work/x.gbt"

# Hardening: outputs never clobber inputs or a previous output, inputs are
# bounded before they are allocated, frames stream from a pipe.
cp "$work/a.gbt" "$work/keep.gbt"
expect 2 "is also an input" $g track --table "$work/keep.gbt" --frames "$d/frames.y4m" --init "$init0" -o "$work/keep.gbt"
cmp -s "$work/a.gbt" "$work/keep.gbt" || fail "track -o TABLE changed the table"
cp "$d/frames.y4m" "$work/keep.y4m"
expect 2 "is also an input" $g track --table "$work/a.gbt" --frames "$work/keep.y4m" --init "$init0" -o "$work/keep.y4m"
cmp -s "$d/frames.y4m" "$work/keep.y4m" || fail "track -o FRAMES changed the frames"
expect 2 "is also an input" $g track --table "$work/a.gbt" --frames "$d/frames.y4m" --init "$init0" --stats "$work/a.gbt"
cp "$d/model.pgm" "$work/keep.pgm"
expect 2 "is also an input" $g tables build --model "$work/keep.pgm" --binary --x 0:0:1 --y 0:0:1 -o "$work/keep.pgm"
cmp -s "$d/model.pgm" "$work/keep.pgm" || fail "tables build -o MODEL changed the model"
expect 2 "is also an input" $g synth --shape "$d/model.csv" --frames 2 -o "$d"
# A failed run leaves the previous output as it was, and no temporary behind.
cp "$work/one.csv" "$work/prev.csv"
expect 1 "not a Y4M" $g track --table "$work/a.gbt" --frames "$d/gt.csv" --init "$init0" -o "$work/prev.csv"
cmp -s "$work/one.csv" "$work/prev.csv" || fail "a failed track clobbered its previous output"
cp "$work/a.gbt" "$work/prev.gbt"
expect 1 "kept none" $g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --keep 1e-9 --decimation global -o "$work/prev.gbt"
cmp -s "$work/a.gbt" "$work/prev.gbt" || fail "a failed tables build clobbered the previous table"
[ -z "$(find "$work" -maxdepth 1 -name '.*.tmp.*')" ] || fail "temporary files left behind: $(ls -a "$work")"
# Frames from a pipe, standard input and a FIFO: the same poses as the file.
$g track --table "$work/a.gbt" --frames - --init "$init0" --plain --voter csr -o "$work/stdin.csv" < "$d/frames.y4m" 2>/dev/null || fail "track --frames -"
cmp -s "$work/one.csv" "$work/stdin.csv" || fail "--frames - gave other poses"
cat "$d/frames.y4m" | $g track --table "$work/a.gbt" --frames - --init "$init0" --plain --voter csr > "$work/piped.csv" 2>/dev/null || fail "track from a pipe"
cmp -s "$work/one.csv" "$work/piped.csv" || fail "a pipe gave other poses"
mkfifo "$work/fifo"
cat "$d/frames.y4m" > "$work/fifo" &
$g track --table "$work/a.gbt" --frames "$work/fifo" --init "$init0" --plain --voter csr -o "$work/fifo.csv" 2>/dev/null || fail "track from a FIFO"
wait
cmp -s "$work/one.csv" "$work/fifo.csv" || fail "a FIFO gave other poses"
# Headers are checked before anything is allocated, and against the file.
printf 'YUV4MPEG2 W32768 H32768 Cmono\nFRAME\n' > "$work/huge.y4m"
expect 1 "bad Y4M width" $g track --table "$work/a.gbt" --frames "$work/huge.y4m" --init 1,1
printf 'YUV4MPEG2 W8192 H8192 Cmono\nFRAME\nabc' > "$work/claims.y4m"
expect 1 "frame 0: truncated (the header says 8192x8192" $g track --table "$work/a.gbt" --frames "$work/claims.y4m" --init 1,1
printf 'P5\n16384 4096\n255\nabc' > "$work/claims.pgm"
expect 1 "truncated PGM pixel data (the header says 16384x4096)" $g tables build --model "$work/claims.pgm" --binary --x 0:0:1 --y 0:0:1 -o "$work/x.gbt"
printf 'YUV4MPEG2 W8 H8 C420p10\nFRAME\n' > "$work/p10.y4m"
expect 1 "C420p10 not supported (8-bit only" $g track --table "$work/a.gbt" --frames "$work/p10.y4m" --init 1,1 -o "$work/p10.csv"
[ ! -e "$work/p10.csv" ] || fail "a pose written before the colourspace error"
printf 'YUV4MPEG2 W8 W9 H8 Cmono\n' > "$work/twice.y4m"
expect 1 "gives W twice" $g track --table "$work/a.gbt" --frames "$work/twice.y4m" --init 1,1
printf 'YUV4MPEG2 W8 H8 Cmono\r\nFRAME\n' > "$work/crlf.y4m"
expect 1 "carriage return" $g track --table "$work/a.gbt" --frames "$work/crlf.y4m" --init 1,1
{ printf 'P5 2 2 255 # comment\n'; printf 'abcd'; } > "$work/comment.pgm"
expect 1 "a comment after maxval" $g tables build --model "$work/comment.pgm" --binary --x 0:0:1 --y 0:0:1 -o "$work/x.gbt"
# Tables beyond the limits are refused when built, before the stencils.
expect 1 "a table may reach at most 1023 px" $g tables build --model "$d/model.pgm" --binary --ref 16384,16384 --x 0:0:1 --y 0:0:1 -o "$work/x.gbt"
expect 1 "would exceed" $g tables build --model-points "$d/model.csv" --binary --x -1000:1000:4096 --y -1000:1000:4096 -o "$work/x.gbt"
expect 2 "must lie within +-1024 pixels" $g tables build --model-points "$d/model.csv" --binary --x -2000:0:3 --y 0:0:1 -o "$work/x.gbt"
expect 2 "as 32-bit floats" $g tables build --model-points "$d/model.csv" --binary --x 1:1.00000001:2 --y 0:0:1 -o "$work/x.gbt"
expect 1 "too small to store" $g tables build --model-points "$d/model.csv" --binary --x 0:0:1 --y 0:0:1 --keep 1e-300 -o "$work/x.gbt"
# Readers of CSVs: no silently skipped first line, no NaN, no wrapped frame numbers.
printf '10;20\n1,2\n' > "$work/semicolon.csv"
expect 1 "semicolon.csv:1: expected integer" $g tables build --model-points "$work/semicolon.csv" --binary --x 0:0:1 --y 0:0:1 -o "$work/x.gbt"
printf 'frame,x,y,theta_deg,depth\n0,nan,1,0,0\n' > "$work/nan.csv"
expect 1 "nan.csv:2: malformed row" $g eval --poses "$work/nan.csv" --gt "$d/gt.csv"
printf 'frame,x,y,theta_deg,depth\n4294967296,1,1,0,0\n' > "$work/wrap.csv"
expect 1 "wrap.csv:2: malformed row" $g eval --poses "$work/wrap.csv" --gt "$d/gt.csv"
printf 'frame,x,y,theta_deg,depth\n-1,1,1,0,0\n' > "$work/negative.csv"
expect 1 "negative.csv:2: malformed row" $g eval --poses "$work/negative.csv" --gt "$d/gt.csv"
expect 2 "want WxH with 8 <= W,H <= 8192" $g synth --shape curve --size 4294967304x8 -o "$work/x"
# Compact offsets (format 1.2, the default) and u32 offsets hold the same
# lists: the same poses, fewer bytes.
$g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --keep 0.2 --offsets wide -o "$work/wide.gbt" 2>/dev/null
$g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --keep 0.2 -o "$work/compact.gbt" 2>/dev/null
[ "$(od -An -tu2 -j10 -N2 "$work/wide.gbt" | tr -d ' ')" = 0 ] || fail "--offsets wide is not format 1.0"
[ "$(od -An -tu2 -j10 -N2 "$work/compact.gbt" | tr -d ' ')" = 2 ] || fail "the default table is not format 1.2"
[ "$(stat -c %s "$work/compact.gbt")" -lt "$(stat -c %s "$work/wide.gbt")" ] || fail "compact offsets are not smaller"
$g track --plain --table "$work/wide.gbt" --frames "$d/frames.y4m" --init "$init0" -o "$work/wide.csv" 2>/dev/null
$g track --plain --table "$work/compact.gbt" --frames "$d/frames.y4m" --init "$init0" -o "$work/compact.csv" 2>/dev/null
cmp -s "$work/wide.csv" "$work/compact.csv" || fail "compact and u32 offsets track differently"
expect 2 "want compact or wide" $g tables build --model-points "$d/model.csv" --binary --x 0:0:1 --y 0:0:1 --offsets narrow -o "$work/x.gbt"
# tables analyse: JSON with the margin, plots on request.
$g tables analyse "$work/compact.gbt" --plots "$work/plots" -o "$work/analysis.json" 2>/dev/null || fail "tables analyse failed"
grep -q '"overall_margin": [0-9]' "$work/analysis.json" || fail "no overall_margin in the analysis"
grep -q '"margins_exact": true' "$work/analysis.json" || fail "1-pixel translation cells not marked exact"
[ -s "$work/plots/overlap_map.svg" ] && [ -s "$work/plots/margins.svg" ] || fail "analysis plots missing"
for svg in "$work"/plots/*.svg; do
  python3 -c 'import sys, xml.etree.ElementTree as ET; sys.exit(0 if ET.parse(sys.argv[1]).getroot().tag.endswith("svg") else 1)' "$svg" \
    || fail "$svg is not a well-formed SVG document"
done
expect 2 "give exactly one TABLE" $g tables analyse "$work/compact.gbt" "$work/wide.gbt"
# Budgets: the table fits, and the report says what was reached.
half_kept=$(stat -c %s "$work/a.gbt")  # keep 0.5
$g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --max-bytes 20000 -o "$work/budget.gbt" 2> "$work/budget.txt"
[ "$(stat -c %s "$work/budget.gbt")" -le 20000 ] || fail "--max-bytes 20000 gave $(stat -c %s "$work/budget.gbt") bytes"
[ "$(stat -c %s "$work/budget.gbt")" -ge 19000 ] || fail "--max-bytes 20000 left more than 5% unused"
grep -q "margin of error [0-9]* px (exact" "$work/budget.txt" || fail "the budget report has no margin"
grep -q "noise tolerance" "$work/budget.txt" || fail "the budget report has no noise tolerance"
$g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --min-margin 30 -o "$work/margin.gbt" 2>/dev/null
$g tables analyse "$work/margin.gbt" --samples 0 -o "$work/margin.json" 2>/dev/null || fail "tables analyse failed"
margin=$(sed -n 's/^  "overall_margin": \([0-9]*\),$/\1/p' "$work/margin.json")
[ -n "$margin" ] && [ "$margin" -ge 30 ] || fail "--min-margin 30 not met (margin '$margin')"
expect 2 "exclude each other" $g tables build --model-points "$d/model.csv" --binary --x 0:0:1 --y 0:0:1 --keep 0.5 --max-bytes 9000 -o "$work/x.gbt"
expect 1 "the smallest table this model and space allow" $g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --max-bytes 500 -o "$work/x.gbt"
expect 1 "below --min-margin" $g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --min-margin 100000 -o "$work/x.gbt"
[ ! -e "$work/x.gbt" ] || fail "a refused budget wrote a table"
# Template reduction: fewer points, a smaller table.
$g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --reduce-template 10 -o "$work/reduced.gbt" 2> "$work/reduced.txt"
grep -q "characterising value [0-9]*" "$work/reduced.txt" || fail "no template reduction report"
[ "$(stat -c %s "$work/reduced.gbt")" -lt "$half_kept" ] || fail "the reduced template's table is not smaller"
expect 2 "translation spaces" $g tables build --model-points "$d/model.csv" --binary --x -5:5:11 --y -5:5:11 --theta -1:1:3 --reduce-template 5 -o "$work/x.gbt"
echo "1 passed, 0 failed"
