#!/usr/bin/env bash
# Jobs from `gabarit hil lava-job`, run by LAVA's dispatcher alone (lava-run,
# no server) on the HIL firmware in QEMU (docs/hil-farm.md).
#   pass    the job completes; one test case per frame (pass, or skip for the
#           two frames faults were planned on) and one per check (all pass);
#           the harness's report is in the job's folder, every check passed
#   faults  a board whose firmware refuses the run (no table where it looks):
#           complete, with the handshake's case failed; a board that never
#           boots (QEMU refuses its images): incomplete, Infrastructure; a
#           hung firmware (a reset handler that spins): incomplete, Test
#           (the monitors time out), and the harness's report says why; a
#           firmware with a bug on one frame (FAULTY_ELF, frame 5's pose a
#           pixel off): complete, with that frame's case failed, its error
#           against gt.csv as the measurement, and the pose check failed
# Usage: lava_run_test.sh GABARIT FIRMWARE_ELF MACHINE HIL_LAVA_DIR [pass|faults FAULTY_ELF]
# Exit 77 (skipped) without lava-run or python3-jinja2, or as a user who
# cannot write LAVA's folders.
set -euo pipefail
gabarit=$1 firmware=$2 machine=$3 templates=$4 scenario=${5:-pass} faulty=${6:-}
command -v lava-run > /dev/null || { echo "SKIP: no lava-run (apt-get install lava-dispatcher)"; exit 77; }
python3 -c "import jinja2, yaml" 2> /dev/null || { echo "SKIP: no python3-jinja2"; exit 77; }
[ -w /var/lib/lava/dispatcher ] || [ -w /var/lib/lava ] || { echo "SKIP: lava-run needs /var/lib/lava/dispatcher writable (root)"; exit 77; }
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d /tmp/gabarit-lava-XXXXXX)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
cd "$work"
frames=24
[ "$scenario" = faults ] && frames=8
"$gabarit" synth --shape curve --frames $frames --noise 0.02 --size 96x96 --seed 11 -o seq > /dev/null
"$gabarit" tables build --model seq/model.pgm --binary --x -4:4:9 --y -4:4:9 -o seq/table.gbt > /dev/null

# run_job NAME FIRMWARE [lava-job options]: writes the job into NAME, renders
# a worker's device for it (a free port for the board's HIL link, as the
# lab's device dictionary would declare it) and runs it; NAME/status holds
# lava-run's exit status and NAME/lava.log its log.
run_job() {
  local name=$1 elf=$2
  shift 2
  "$gabarit" hil lava-job --sequence seq --firmware "$elf" --device-type "gabarit-qemu-$machine" --out "$name" "$@"
  local port
  port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  printf "{%% extends 'gabarit-qemu-%s.jinja2' %%}\n{%% set gabarit_link_port = %s %%}\n{%% set gabarit = '%s' %%}\n" \
    "$machine" "$port" "$gabarit" > "$name.jinja2"
  python3 "$templates/render_device.py" "$name.jinja2" --context gabarit_bundle="$work/$name" > "$name.device.yaml"
}
launch() {
  local name=$1 status=0
  timeout 600 lava-run --job-id "gabarit-$name-$$" --output-dir "$work/out-$name" --device "$name.device.yaml" \
    "$name/job.yaml" > "$name/lava.log" 2>&1 || status=$?
  echo $status > "$name/status"
  # The replayer writes its report once the run is judged, after the console's last line.
  for _ in $(seq 100); do [ -f "$name/report/summary.json" ] || [ ! -f "$name/replay.log" ] && break; sleep 0.2; done
}

if [ "$scenario" = pass ]; then
  # Two frames carry a fault (a corrupted fragment, then a dropped one): the
  # harness judges them by the fault's check, and LAVA shows them as skips.
  run_job ok "$firmware" --faults "cycle:9:corrupt,drop" --minutes 5
  launch ok
  python3 "$here/lava_results.py" ok --frames 24 --skipped frame_000009,frame_000018 --checks-pass
else
  # move_table JOB ADDRESS: the job loads the table there instead of the slot.
  move_table() { sed -i "s/,addr=0x[0-9a-f]*,force-raw/,addr=$2,force-raw/" "$1/job.yaml"; grep -q "addr=$2," "$1/job.yaml"; }
  slot=$(nm "$firmware" | awk '$3 == "gabarit_table_slot" { print $1 }')
  # A board whose firmware refuses the run: the table lands 64 KiB past the
  # slot, which the firmware finds empty, and it says so in CAPS.
  run_job refused "$firmware" --minutes 2
  move_table refused "$(printf '0x%08x' $((0x$slot + 0x10000)))"
  # A board that never boots: the table over the firmware's vector table,
  # which QEMU refuses to load.
  run_job neverboots "$firmware" --minutes 2
  move_table neverboots 0x00000000
  # A hung firmware: a reset handler that spins, with the table slot's
  # symbols so that the job writer accepts it.
  printf '    .syntax unified\n    .thumb\n    .section .vectors, "a"\n    .word 0x20001000\n    .word reset + 1\n    .text\n    .thumb_func\n    .global _start\n_start:\nreset:\n    b reset\n' > hung.S
  arm-none-eabi-gcc -mcpu=cortex-m7 -nostdlib -Wl,--section-start=.vectors=0 -Wl,-Ttext=0x400 \
    -Wl,--defsym=gabarit_table_slot=0x20010000 -Wl,--defsym=gabarit_table_slot_end=0x20020000 hung.S -o hung.elf
  run_job hung hung.elf --minutes 1
  run_job faulty "${faulty:?faults wants FAULTY_ELF}" --minutes 2
  for job in refused neverboots hung faulty; do launch $job; done
  status=0
  python3 "$here/lava_results.py" refused --frames 0 --failed-check handshake || status=1
  python3 "$here/lava_results.py" neverboots --incomplete Infrastructure || status=1
  python3 "$here/lava_results.py" hung --incomplete Test --report-error "did not answer HELLO" || status=1
  python3 "$here/lava_results.py" faulty --frames $frames --failed-frame frame_000005 --failed-check poses_match_reference || status=1
  exit $status
fi
