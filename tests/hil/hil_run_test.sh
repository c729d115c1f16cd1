#!/usr/bin/env bash
# hil_run_test.sh GABARIT DUT SCENARIO [gabarit hil run options...]
# Generates a sequence, builds its table, runs `gabarit hil run` into the DUT
# and checks the report, not only the exit status:
#   binary  the thesis's curve, binary, 2-DOF; every frame a pose, all
#           bit-identical to the host's reference
#   scene   a grayscale 4-DOF scene (photographed object, 2-depth focus
#           stack, rotation); the same
#   faults  the binary sequence with 5% of its frames faulted at random: every
#           frame accounted for, poses in order, every fault in the JUnit file,
#           detected and recovered from
#   plan    each fault kind once, from a plan file, on 24 small frames (48x48)
#   soak    10^4 small binary frames with 1% faulted (80x80; 40x40 on cortex-m)
# Sizes shrink for the cortex-m DUT (QEMU's UART moves about 12 KB/s).
set -euo pipefail
g=${1:?usage: hil_run_test.sh GABARIT DUT SCENARIO [options]}
dut=${2:?}
scenario=${3:?}
shift 3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
seq=$work/seq
small=0
[ "$dut" = cortex-m ] && small=1
faults=()
case "$scenario" in
  binary|faults)
    if [ $small = 1 ]; then size=96x96 frames=12; else size=160x160 frames=120; fi
    [ "$scenario" = faults ] && { frames=$((frames * 2)); faults=(--faults random:0.05 --seed 4); }
    "$g" synth --shape curve --frames $frames --max-step 3 --noise 0.02 --size $size --seed 3 -o "$seq" 2> /dev/null
    "$g" tables build --model "$seq/model.pgm" --binary --x -4:4:9 --y -4:4:9 -o "$seq/table.gbt" 2> /dev/null ;;
  scene)
    if [ $small = 1 ]; then frames=5; else frames=40; fi
    "$g" synth --scene coin --depths 2 --motion spin --occlusion 0:0 --frames $frames --size 180x140 --seed 2 -o "$seq" 2> /dev/null
    "$g" tables build --model "$seq"/model_0*.pgm --x -3:3:7 --y -3:3:7 --theta -1.5:1.5:5 -o "$seq/table.gbt" 2> /dev/null ;;
  plan)
    frames=24
    "$g" synth --shape random --points 30 --frames $frames --max-step 2 --noise 0.02 --size 48x48 --seed 6 -o "$seq" 2> /dev/null
    "$g" tables build --model "$seq/model.pgm" --binary --x -3:3:7 --y -3:3:7 -o "$seq/table.gbt" 2> /dev/null
    printf '3 drop\n6 duplicate\n9 reorder\n12 corrupt\n15 bitflip\n18 restart\n' > "$work/plan.txt"
    faults=(--faults "$work/plan.txt") ;;
  soak)
    frames=10000
    if [ $small = 1 ]; then  # 40x40 frames: about 25 minutes through QEMU's UART
      "$g" synth --shape random --points 24 --frames $frames --max-step 2 --noise 0.02 --size 40x40 --seed 12 -o "$seq" 2> /dev/null
      "$g" tables build --model "$seq/model.pgm" --binary --x -3:3:7 --y -3:3:7 -o "$seq/table.gbt" 2> /dev/null
    else
      "$g" synth --shape random --points 60 --frames $frames --max-step 3 --noise 0.02 --size 80x80 --seed 11 -o "$seq" 2> /dev/null
      "$g" tables build --model "$seq/model.pgm" --binary --x -4:4:9 --y -4:4:9 -o "$seq/table.gbt" 2> /dev/null
    fi
    faults=(--faults random:0.01 --seed 3) ;;
  *) echo "unknown scenario $scenario"; exit 2 ;;
esac
status=0
"$g" hil run --dut "$dut" --sequence "$seq" --report "$work/report" "${faults[@]}" "$@" 2> "$work/stderr" || status=$?
tail -3 "$work/stderr"
python3 - "$work/report" "$scenario" "$status" <<'PY'
import json, sys, xml.etree.ElementTree as ET
report, scenario, status = sys.argv[1], sys.argv[2], int(sys.argv[3])
s = json.load(open(f"{report}/summary.json"))
problems = []
def need(ok, what):
    if not ok: problems.append(what)
need(status == 0, f"gabarit hil run exited {status}")
need(s["error"] == "", f"the run stopped: {s['error']}")
need(s["unaccounted"] == 0, f"{s['unaccounted']} frames unaccounted for")
need(s["out_of_order"] == 0, f"{s['out_of_order']} poses out of order")
need(s["poses_matching_reference"] == s["poses"], f"{s['poses'] - s['poses_matching_reference']} poses differ from the reference")
need(s["checks_failed"] == 0, f"{s['checks_failed']} checks failed")
if scenario in ("binary", "scene"):
    need(s["poses"] == s["frames"], f"{s['poses']} poses for {s['frames']} frames")
    need(s["latency_us"]["samples"] == s["frames"], "latency not measured on every frame")
else:
    need(len(s["faults"]) > 0, "no fault was injected")
    need(all(f["detected"] and f["recovered"] for f in s["faults"]), "a fault was not detected or not recovered from")
    if scenario == "plan":
        kinds = sorted(f["kind"] for f in s["faults"])
        need(kinds == sorted(["drop", "duplicate", "reorder", "corrupt", "bitflip", "restart"]), f"the plan's faults: {kinds}")
suite = ET.parse(f"{report}/junit.xml").getroot().find("testsuite")
names = [t.get("name") for t in suite.findall("testcase")]
need(len(names) == len(s["checks"]), "the JUnit file does not have one testcase per check")
for i, f in enumerate(s["faults"]):
    need(f"fault.{i}.{f['kind']}.frame{f['frame']}" in names, f"fault {i} is not in the JUnit file")
props = {p.get("name") for p in suite.find("properties")}
need({"latency_us.p50", "latency_us.p99", "latency_us.max", "overhead.bytes_per_frame"} <= props, "JUnit properties missing")
for f in ("frames.csv", "poses.csv", "results.jsonl", "faults.csv", "report.md", "latency.svg", "faults.svg"):
    try:
        open(f"{report}/{f}").close()
    except OSError:
        problems.append(f"{f} missing")
for f in ("latency.svg", "faults.svg"):  # well-formed SVG documents
    try:
        need(ET.parse(f"{report}/{f}").getroot().tag.endswith("svg"), f"{f}: the root element is not svg")
    except (ET.ParseError, OSError) as e:
        problems.append(f"{f}: not well-formed XML ({e})")
lines = open(f"{report}/results.jsonl").read().splitlines()
need(len(lines) == s["frames"], f"results.jsonl has {len(lines)} lines for {s['frames']} frames")
print(f"hil {s['dut']['kind']} {scenario}: {s['frames']} frames, {s['poses']} poses, {len(s['faults'])} faults; "
      f"latency p50 {s['latency_us']['p50']:.0f} us p99 {s['latency_us']['p99']:.0f} us max {s['latency_us']['max']:.0f} us; "
      f"DUT p50 {s['dut_time_us']['p50']:.1f} us; overhead {s['overhead_per_frame']['bytes']:.0f} B, "
      f"{s['overhead_per_frame']['host_us']:.1f} us per frame")
if problems:
    print("FAIL: " + "; ".join(problems))
    sys.exit(1)
print("PASS")
PY
