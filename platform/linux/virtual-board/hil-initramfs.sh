#!/usr/bin/env bash
# Builds the virtual board's initramfs for a HIL run (hil-init.sh as /init):
# busybox, the aarch64 board application and relay with their shared
# libraries (libusb, and libudev under it), the modules prepare.sh cached,
# the table, the USB gadget script.
#
# usage: hil-initramfs.sh --cache DIR --board BIN --relay BIN --table T --window WxH --serial S --out FILE [--profile F]
# --profile: a session profile the board runs (gabarit-board --profile), e.g. the particle tracker.
set -euo pipefail
profile=
here=$(cd "$(dirname "$0")" && pwd)
while [ $# -gt 0 ]; do
  case "$1" in
    --cache) cache=$2; shift 2 ;;
    --board) board=$2; shift 2 ;;
    --relay) relay=$2; shift 2 ;;
    --table) table=$2; shift 2 ;;
    --window) window=$2; shift 2 ;;
    --serial) serial=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --profile) profile=$2; shift 2 ;;
    *) echo "hil-initramfs.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
for f in "$board" "$relay" "$table" "$cache/busybox" "$cache/modules/order" ${profile:+"$profile"}; do
  [ -f "$f" ] || { echo "hil-initramfs.sh: $f is missing" >&2; exit 1; }
done
root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
mkdir -p "$root"/{bin,lib,lib/aarch64-linux-gnu,modules,data,proc,sys,dev,tmp,etc}
cp "$cache/busybox" "$root/bin/busybox"
cp "$board" "$root/bin/gabarit-board"
cp "$relay" "$root/bin/gabarit-hil-relay"
cp "$here/../usb-gadget.sh" "$root/bin/usb-gadget.sh"
sysroot=/usr/aarch64-linux-gnu/lib
multiarch=/usr/lib/aarch64-linux-gnu
cp "$sysroot/ld-linux-aarch64.so.1" "$root/lib/"
for lib in libc.so.6 libm.so.6 libstdc++.so.6 libgcc_s.so.1 libpthread.so.0; do cp -L "$sysroot/$lib" "$root/lib/aarch64-linux-gnu/"; done
# libusb (and libudev, which it links) from Debian's arm64 packages.
for lib in libusb-1.0.so.0 libudev.so.1; do cp -L "$multiarch/$lib" "$root/lib/aarch64-linux-gnu/"; done
cp "$cache"/modules/*.ko "$cache/modules/order" "$root/modules/"
cp "$table" "$root/data/table.gbt"
printf 'WINDOW=%s\nSERIAL=%s\n' "$window" "$serial" > "$root/data/params.sh"
if [ -n "$profile" ]; then
  cp "$profile" "$root/data/session.profile"
  echo "PROFILE=/data/session.profile" >> "$root/data/params.sh"
fi
echo "$serial" > "$root/etc/machine-id"
cp "$here/hil-init.sh" "$root/init"
chmod +x "$root/init" "$root/bin/usb-gadget.sh"
(cd "$root" && find . | cpio -o -H newc --quiet | gzip -1) > "$out.part"
mv "$out.part" "$out"
