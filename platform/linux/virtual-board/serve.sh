#!/usr/bin/env bash
# Boots the virtual board as a HIL DUT and leaves it running, its relay on a
# TCP port of 127.0.0.1 (QEMU's chardev as the server), as a real board's
# relay would be on its serial line: for `gabarit hil run --dut board:FILE`
# (hil/boards/virtual-board-tcp.yaml). It powers off after the run's BYE.
#
# usage: serve.sh --cache DIR --board BIN --relay BIN --table T --window WxH --port N --log FILE
#                 [--console-port N]
#        serve.sh ... --bundle DIR ...  (the table and window of a job from
#                 `gabarit hil lava-job`: DIR/table.gbt, DIR/sequence/frames.y4m's size)
# --console-port: the board's console (its first UART) on a TCP port of
# 127.0.0.1 instead of in the log, as a lab's console server (ser2net) would
# serve a real board's; console.sh connects to it (docs/hil-farm.md).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
serial=gabarit-vb-0001
console_port=""
while [ $# -gt 0 ]; do
  case "$1" in
    --cache) cache=$2; shift 2 ;;
    --board) board=$2; shift 2 ;;
    --relay) relay=$2; shift 2 ;;
    --table) table=$2; shift 2 ;;
    --window) window=$2; shift 2 ;;
    --port) port=$2; shift 2 ;;
    --log) log=$2; shift 2 ;;
    --console-port) console_port=$2; shift 2 ;;
    --bundle)
      table=$2/table.gbt
      # A Y4M stream's header: YUV4MPEG2 W<width> H<height> ...
      window=$(head -c 256 "$2/sequence/frames.y4m" | head -n 1 | awk '{ for (i = 2; i <= NF; ++i) { if ($i ~ /^W/) w = substr($i, 2); if ($i ~ /^H/) h = substr($i, 2) } } END { print w "x" h }')
      shift 2 ;;
    *) echo "serve.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bash "$here/hil-initramfs.sh" --cache "$cache" --board "$board" --relay "$relay" --table "$table" --window "$window" \
  --serial "$serial" --out "$work/initramfs.cpio.gz"
console=(-nographic)
[ -z "$console_port" ] || console=(-display none -monitor none -serial "tcp:127.0.0.1:$console_port,server=on,wait=off")
exec qemu-system-aarch64 -M virt -cpu cortex-a72 -smp 2 -m 1024 "${console[@]}" -no-reboot -nic none \
  -kernel "$cache/vmlinuz" -initrd "$work/initramfs.cpio.gz" -append "console=ttyAMA0 panic=-1 quiet" \
  -device virtio-serial-device -chardev "socket,id=hil,host=127.0.0.1,port=$port,server=on,wait=off" \
  -device virtserialport,chardev=hil,name=gabarit.hil > "$log" 2>&1
