#!/usr/bin/env bash
# board_tcp_test.sh GABARIT AARCH64_BUILD
# `gabarit hil run --dut board:FILE.yaml` on the path a real board takes: the
# virtual board booted on its own (serve.sh), its relay on TCP, the harness
# connecting to it from a hardware map (a copy of hil/boards/virtual-board-tcp.yaml
# on a free port). 120 frames with a board kill, an unplug and a camera error
# among them; every check must pass.
set -euo pipefail
g=${1:?usage: board_tcp_test.sh GABARIT AARCH64_BUILD}
build=${2:?}
here=$(cd "$(dirname "$0")" && pwd)
vb=$here/../../platform/linux/virtual-board
bash "$vb/prepare.sh" "$build/virtual-board/cache" > /dev/null
work=$(mktemp -d)
qemu=""
trap '[ -n "$qemu" ] && kill $qemu 2>/dev/null; rm -rf "$work"' EXIT
"$g" synth --shape curve --frames 120 --max-step 3 --noise 0.02 --size 160x120 --seed 9 -o "$work/seq" 2> /dev/null
"$g" tables build --model "$work/seq/model.pgm" --binary --x -4:4:9 --y -4:4:9 -o "$work/seq/table.gbt" 2> /dev/null
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
sed "s/^relay: .*/relay: tcp:127.0.0.1:$port/" "$here/../../hil/boards/virtual-board-tcp.yaml" > "$work/board.yaml"
bash "$vb/serve.sh" --cache "$build/virtual-board/cache" --board "$build/platform/linux/gabarit-board" \
  --relay "$build/platform/linux/gabarit-hil-relay" --table "$work/seq/table.gbt" --window 160x120 --port "$port" \
  --log "$work/console.log" &
qemu=$!
status=0
"$g" hil run --dut "board:$work/board.yaml" --sequence "$work/seq" --report "$work/report" \
  --faults cycle:30:board-kill,usb-unplug,camera-error 2> "$work/stderr" || status=$?
grep -v "frames answered" "$work/stderr" | tail -3
wait $qemu || true
qemu=""
grep -q "VIRTUAL-BOARD: HIL DONE 0" "$work/console.log" || { echo "board over TCP: the relay did not end cleanly"; tail -5 "$work/console.log"; exit 1; }
[ $status = 0 ] || { echo "board over TCP: FAIL"; exit 1; }
python3 -c "
import json, sys; s = json.load(open('$work/report/summary.json'))
ok = s['poses'] == 120 and s['poses_matching_reference'] == 120 and len(s['faults']) == 3 and s['checks_failed'] == 0
print('board over TCP:', 'PASS' if ok else 'FAIL', s['poses'], 'poses,', len(s['faults']), 'faults'); sys.exit(0 if ok else 1)"
