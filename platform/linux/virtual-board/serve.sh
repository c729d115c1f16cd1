#!/usr/bin/env bash
# Boots the virtual board as a HIL DUT and leaves it running, its relay on a
# TCP port of 127.0.0.1 (QEMU's chardev as the server), as a real board's
# relay would be on its serial line: for `gabarit hil run --dut board:FILE`
# (hil/boards/virtual-board-tcp.yaml). It powers off after the run's BYE.
#
# usage: serve.sh --cache DIR --board BIN --relay BIN --table T --window WxH --port N --log FILE
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
serial=gabarit-vb-0001
while [ $# -gt 0 ]; do
  case "$1" in
    --cache) cache=$2; shift 2 ;;
    --board) board=$2; shift 2 ;;
    --relay) relay=$2; shift 2 ;;
    --table) table=$2; shift 2 ;;
    --window) window=$2; shift 2 ;;
    --port) port=$2; shift 2 ;;
    --log) log=$2; shift 2 ;;
    *) echo "serve.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bash "$here/hil-initramfs.sh" --cache "$cache" --board "$board" --relay "$relay" --table "$table" --window "$window" \
  --serial "$serial" --out "$work/initramfs.cpio.gz"
exec qemu-system-aarch64 -M virt -cpu cortex-a72 -smp 2 -m 1024 -nographic -no-reboot -nic none \
  -kernel "$cache/vmlinuz" -initrd "$work/initramfs.cpio.gz" -append "console=ttyAMA0 panic=-1 quiet" \
  -device virtio-serial-device -chardev "socket,id=hil,host=127.0.0.1,port=$port,server=on,wait=off" \
  -device virtserialport,chardev=hil,name=gabarit.hil > "$log" 2>&1
