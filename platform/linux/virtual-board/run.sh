#!/usr/bin/env bash
# The virtual-board test: Debian's arm64 kernel in qemu-system-aarch64 with
# vivid (camera) and gpio-sim (GPIO lines), running the aarch64 board
# application on a recorded sequence. Checks, in the guest: the lock and strobe
# lines, the trigger input, surviving the camera's unplug; on the host: the
# board's poses are identical to `gabarit track` on the frames it captured.
#
# usage: run.sh --cache DIR --work DIR --board AARCH64_BOARD_BIN --feed AARCH64_FEED_BIN --gabarit HOST_GABARIT
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
while [ $# -gt 0 ]; do
  case "$1" in
    --cache) cache=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --board) board=$2; shift 2 ;;
    --feed) feed=$2; shift 2 ;;
    --gabarit) gabarit=$2; shift 2 ;;
    *) echo "run.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
for f in "$board" "$feed" "$gabarit"; do
  [ -x "$f" ] || { echo "run.sh: $f is missing (build the release and aarch64 presets)" >&2; exit 1; }
done
start=$SECONDS
bash "$here/prepare.sh" "$cache"
rm -rf "$work" && mkdir -p "$work"

# The recording: the thesis's curve at the size of vivid's S-Video frames.
size=720x480 frames=24 hold_ms=150
"$gabarit" synth --shape curve --frames $frames --max-step 4 --noise 0.05 --seed 11 --size $size -o "$work/seq" 2>/dev/null
"$gabarit" tables build --model "$work/seq/model.pgm" --binary --x -5:5:11 --y -5:5:11 -o "$work/table.gbt" 2>/dev/null
init=$(sed -n 2p "$work/seq/gt.csv" | cut -d, -f2,3)

# The initramfs: busybox, the two arm64 programs and their shared libraries,
# the modules, the inputs.
root=$work/initramfs
mkdir -p "$root"/{bin,lib,lib/aarch64-linux-gnu,modules,data,proc,sys,dev,tmp}
cp "$cache/busybox" "$root/bin/busybox"
cp "$board" "$root/bin/gabarit-board"
cp "$feed" "$root/bin/gabarit-vivid-feed"
sysroot=/usr/aarch64-linux-gnu/lib
cp "$sysroot/ld-linux-aarch64.so.1" "$root/lib/"
for lib in libc.so.6 libm.so.6 libstdc++.so.6 libgcc_s.so.1; do cp -L "$sysroot/$lib" "$root/lib/aarch64-linux-gnu/"; done
cp "$cache"/modules/*.ko "$cache/modules/order" "$root/modules/"
cp "$work/table.gbt" "$root/data/"
cp "$work/seq/frames.y4m" "$root/data/frames.y4m"
printf 'INIT=%s\nSIZE=%s\nHOLD_MS=%s\nFRAMES=%s\n' "$init" "$size" "$hold_ms" "$frames" > "$root/data/params.sh"
cp "$here/guest-init.sh" "$root/init"
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc --quiet | gzip -1) > "$work/initramfs.cpio.gz"

echo "virtual board: booting $(cat "$cache/kernel-version") ($((SECONDS - start)) s so far)"
timeout 600 qemu-system-aarch64 -M virt -cpu cortex-a72 -smp 2 -m 1024 -nographic -no-reboot -nic none \
  -kernel "$cache/vmlinuz" -initrd "$work/initramfs.cpio.gz" -append "console=ttyAMA0 panic=-1 quiet" \
  > "$work/console.log" 2>&1 || true
tr -d '\r' < "$work/console.log" | grep -v '^\[' | grep -E "^virtual-board|VIRTUAL-BOARD|gabarit-" || true
if ! grep -q "VIRTUAL-BOARD: PASS" "$work/console.log"; then
  grep -a "VIRTUAL-BOARD: FAIL" "$work/console.log" || { echo "virtual board: no result marker; the console's end:"; tail -n 30 "$work/console.log"; }
  exit 1
fi

# The host's tracker on exactly the frames the board captured.
tr -d '\r' < "$work/console.log" > "$work/console.txt"
python3 "$here/compare_poses.py" "$work/console.txt" "$work/seq/frames.y4m" "$work/compare"
"$gabarit" track --table "$work/table.gbt" --frames "$work/compare/as_captured.y4m" --init "$init" --binary \
  -o "$work/compare/host.csv" 2>/dev/null
if ! cmp -s "$work/compare/host.csv" "$work/compare/board.csv"; then
  echo "virtual board: FAIL: the board's poses differ from gabarit track on the host:"
  diff "$work/compare/host.csv" "$work/compare/board.csv" | head -n 10
  exit 1
fi
echo "virtual board: PASS: $(($(wc -l < "$work/compare/host.csv") - 1)) poses identical to the host's ($((SECONDS - start)) s)"
