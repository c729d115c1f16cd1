#!/usr/bin/env bash
# A job for LAVA's device type gabarit-board (a board that runs gabarit's
# board application and relay), run by LAVA's dispatcher alone (lava-run)
# on the aarch64 virtual board standing in for a lab's board, as
# docs/hil-farm.md declares one: its power by a script (a lab's PDU), its
# console on a TCP port (a lab's ser2net), its HIL link as its hardware map
# (hil/boards/virtual-board-tcp.yaml) names it. The job completes; one test
# case per frame (pass, or skip for the two the rig faulted) and one per
# check, all passing; the harness's report in the job's folder.
# Usage: lava_board_test.sh GABARIT AARCH64_BUILD HIL_LAVA_DIR
# Exit 77 (skipped) without lava-run or python3-jinja2, or as a user who
# cannot write LAVA's folders.
set -euo pipefail
gabarit=$1 build=$2 templates=$3
command -v lava-run > /dev/null || { echo "SKIP: no lava-run (apt-get install lava-dispatcher)"; exit 77; }
python3 -c "import jinja2, yaml" 2> /dev/null || { echo "SKIP: no python3-jinja2"; exit 77; }
[ -w /var/lib/lava/dispatcher ] || [ -w /var/lib/lava ] || { echo "SKIP: lava-run needs /var/lib/lava/dispatcher writable (root)"; exit 77; }
here=$(cd "$(dirname "$0")" && pwd)
vb=$(cd "$here/../../platform/linux/virtual-board" && pwd)
bash "$vb/prepare.sh" "$build/virtual-board/cache" > /dev/null
work=$(mktemp -d /tmp/gabarit-lava-board-XXXXXX)
trap 'bash "$templates/virtual-board-power.sh" off "$work/power" || true; [ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
cd "$work"
"$gabarit" synth --shape curve --frames 24 --max-step 3 --noise 0.02 --size 160x120 --seed 9 -o seq > /dev/null 2>&1
"$gabarit" tables build --model seq/model.pgm --binary --x -4:4:9 --y -4:4:9 -o seq/table.gbt > /dev/null 2>&1
"$gabarit" hil lava-job --sequence seq --device-type gabarit-board --faults cycle:9:camera-error,usb-unplug --minutes 5 --out job
# The device dictionary and the board's hardware map (its relay on a TCP port).
bash "$templates/virtual-board-device.sh" "$build" "$work/power" "$gabarit" > device.jinja2
python3 "$templates/render_device.py" device.jinja2 --context gabarit_bundle="$work/job" > device.yaml
status=0
timeout 900 lava-run --job-id "gabarit-board-$$" --output-dir "$work/out" --device device.yaml job/job.yaml > job/lava.log 2>&1 || status=$?
echo $status > job/status
for _ in $(seq 100); do [ -f job/report/summary.json ] || [ ! -f job/replay.log ] && break; sleep 0.2; done
python3 "$here/lava_results.py" job --frames 24 --skipped frame_000009,frame_000018 --checks-pass || {
  tail -5 job/replay.log; tail -20 power/serve.log power/qemu.log 2> /dev/null; exit 1; }
