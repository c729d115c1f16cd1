#!/usr/bin/env bash
# virtual_board_hil.sh GABARIT AARCH64_BUILD [FRAMES [EVERY [LOOPS]]]
# `gabarit hil run --dut virtual-board` end to end: the aarch64 board
# application on the virtual board (vivid, USB FunctionFS through dummy_hcd,
# gpio-sim), FRAMES frames (default 2000) of 160x120 with a fault every EVERY
# frames (default 6), the harness's link faults and the rig's ten kinds in
# turn (each at least 20 times with the defaults); first, 200 frames without
# faults whose poses must be byte for byte `gabarit track`'s. Checks the report, not only
# the exit status: every check passed, every frame accounted for, poses in
# order and bit-identical to the host's reference, each kind injected about
# FRAMES/EVERY/15 times (22 with the defaults), each fault detected and tracking
# again within 1 s of its end. Prints the figures. LOOPS > 1 is a soak: the
# sequence played LOOPS times over (--soak), its memory and latency drift
# printed from soak.csv.
set -euo pipefail
g=${1:?usage: virtual_board_hil.sh GABARIT AARCH64_BUILD [FRAMES [EVERY]]}
build=${2:?}
frames=${3:-2000}
every=${4:-6}
loops=${5:-1}
soak=()
[ "$loops" -gt 1 ] && soak=(--soak "$loops" --soak-window 2000)
here=$(cd "$(dirname "$0")" && pwd)
bash "$here/../../platform/linux/virtual-board/prepare.sh" "$build/virtual-board/cache" > /dev/null
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$g" synth --shape curve --frames "$frames" --max-step 3 --noise 0.02 --size 160x120 --seed 7 -o "$work/seq" 2> /dev/null
"$g" tables build --model "$work/seq/model.pgm" --binary --x -4:4:9 --y -4:4:9 -o "$work/seq/table.gbt" 2> /dev/null
if [ "$loops" = 1 ]; then
  # Without faults, the poses are byte for byte `gabarit track`'s on the same frames.
  "$g" synth --shape curve --frames 200 --max-step 3 --noise 0.02 --size 160x120 --seed 8 -o "$work/clean" 2> /dev/null
  "$g" tables build --model "$work/clean/model.pgm" --binary --x -4:4:9 --y -4:4:9 -o "$work/clean/table.gbt" 2> /dev/null
  "$g" hil run --dut virtual-board --virtual-board "$build" --sequence "$work/clean" --report "$work/clean-report" 2> /dev/null ||
    { echo "virtual board HIL: FAIL: the run without faults failed"; exit 1; }
  "$g" track --table "$work/clean/table.gbt" --frames "$work/clean/frames.y4m" \
    --init "$(sed -n 2p "$work/clean/gt.csv" | cut -d, -f2,3)" -o "$work/clean/track.csv" 2> /dev/null
  cmp -s "$work/clean/track.csv" "$work/clean-report/poses.csv" ||
    { echo "virtual board HIL: FAIL: the board's poses differ from gabarit track's"; diff "$work/clean/track.csv" "$work/clean-report/poses.csv" | head -5; exit 1; }
  echo "virtual board HIL: 200 poses over USB byte-identical to gabarit track's"
  # The particle tracker from a session profile (gabarit-board --profile): CAPS
  # says so, and 40 poses are byte for byte `gabarit track --tracker particle`'s.
  printf 'gabarit-session-profile 1\ntracker = particle\n' > "$work/particle.profile"
  "$g" hil run --dut virtual-board --virtual-board "$build" --profile "$work/particle.profile" --sequence "$work/clean" \
    --frames 40 --report "$work/particle-report" 2> /dev/null ||
    { echo "virtual board HIL: FAIL: the particle tracker's run failed"; exit 1; }
  "$g" track --tracker particle --table "$work/clean/table.gbt" --frames "$work/clean/frames.y4m" \
    --init "$(sed -n 2p "$work/clean/gt.csv" | cut -d, -f2,3)" -o "$work/clean/particle.csv" 2> /dev/null
  grep -q '"mode": [0-9]*' "$work/particle-report/summary.json" &&
    [ $(( $(grep -o '"mode": [0-9]*' "$work/particle-report/summary.json" | head -1 | grep -o '[0-9]*$') & 1024 )) != 0 ] ||
    { echo "virtual board HIL: FAIL: the board does not report the particle tracker in CAPS"; exit 1; }
  cmp -s <(head -41 "$work/clean/particle.csv") "$work/particle-report/poses.csv" ||
    { echo "virtual board HIL: FAIL: the board's particle poses differ from gabarit track's"; exit 1; }
  echo "virtual board HIL: 40 particle-tracker poses over USB byte-identical to gabarit track --tracker particle's"
fi
kinds=drop,duplicate,reorder,corrupt,bitflip,camera-error,camera-drop,sequence-wrap,camera-disconnect,module-reload
kinds=$kinds,usb-stall,usb-unplug,usb-timeout,board-kill,usb-corrupt
start=$SECONDS
status=0
"$g" hil run --dut virtual-board --virtual-board "$build" --sequence "$work/seq" --report "$work/report" \
  --faults "cycle:$every:$kinds" "${soak[@]}" 2> "$work/stderr" || status=$?
seconds=$((SECONDS - start))
grep -v "frames answered" "$work/stderr" | tail -5
python3 - "$work/report" "$status" "$seconds" "$((frames * loops))" "$every" <<'PY'
import collections, json, sys
report, status, seconds, frames, every = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
s = json.load(open(f"{report}/summary.json"))
problems = []
if status != 0: problems.append(f"exit status {status}")
if s["checks_failed"]: problems += [c["name"] + ": " + c["message"] for c in s["checks"] if not c["passed"]][:10]
if s["unaccounted"] or s["out_of_order"] or s["double_answers"]:
    problems.append(f"unaccounted {s['unaccounted']}, out of order {s['out_of_order']}, double {s['double_answers']}")
if s["poses"] != s["poses_matching_reference"]: problems.append("poses not bit-identical to the reference")
by_kind = collections.defaultdict(list)
for f in s["faults"]: by_kind[f["kind"]].append(f)
want = len(s["faults"]) // 15  # the cycle gives each kind this many, or one more
if len(s["faults"]) < frames // every - 1: problems.append(f"only {len(s['faults'])} faults injected")
for kind, fs in sorted(by_kind.items()):
    rec = [f["recovery_ms"] for f in fs if "recovery_ms" in f]
    bad = [f for f in fs if not (f["detected"] and f["recovered"])]
    print(f"  {kind:18s} {len(fs):3d} injected, {len(fs) - len(bad):3d} detected and recovered"
          + (f", tracking again after {max(rec):.0f} ms at most" if rec else ""))
    if len(fs) < want: problems.append(f"{kind}: only {len(fs)} injected (want {want})")
    problems += [f"{kind} at frame {f['frame']}: {f['evidence']}" for f in bad][:3]
if len(by_kind) != 15: problems.append(f"{len(by_kind)} fault kinds injected, want 15")
st = s["stages_us"]
print(f"virtual board HIL: {s['frames']} frames, {s['poses']} poses ({s['poses_matching_reference']} bit-identical), "
      f"{len(s['faults'])} faults, {s['restarts']['by_the_rig']} board restarts, {seconds} s; latency p50 "
      f"{s['latency_us']['p50'] / 1000:.1f} ms; camera p50 {st['camera']['p50'] / 1000:.1f} ms, tracking p50 "
      f"{st['track']['p50'] / 1000:.2f} ms, strobe p50 {st['strobe']['p50'] / 1000:.2f} ms ({st['strobe']['samples']} edges)")
soak = s.get("soak")
if soak:
    print(f"soak: {soak['samples']} samples; host RSS {soak['host_rss_kib'][0]} -> {soak['host_rss_kib'][1]} KiB, board RSS "
          f"{soak['dut_rss_kib'][0]} -> {soak['dut_rss_kib'][1]} KiB, latency p50 {soak['latency_p50_us'][0] / 1000:.1f} -> "
          f"{soak['latency_p50_us'][1] / 1000:.1f} ms")
    print(open(f"{report}/soak.csv").read())
if problems:
    print("virtual board HIL: FAIL"); [print("  " + p) for p in problems]; sys.exit(1)
print("virtual board HIL: PASS")
PY
