#!/bin/sh
# Makes (or removes) the board's USB gadget for `gabarit-board --link usb`:
# a configfs gadget with one FunctionFS function, its identity (vendor,
# product, serial), and FunctionFS mounted where the board application opens
# it. The application writes the function's descriptors and binds the gadget
# to the USB device controller itself (--usb-gadget), as it must happen after
# the descriptors. POSIX sh: runs under busybox and on a board's distribution.
#
# usage: usb-gadget.sh up [--name N] [--vid 0xVVVV] [--pid 0xPPPP] [--serial S] [--ffs-dir DIR]
#        usb-gadget.sh down [--name N] [--ffs-dir DIR]
# Defaults: name gabarit, 0x1d6b:0x0104 (Linux's composite gadget IDs: use
# your own vendor's in a product), serial from /etc/machine-id or "0",
# FunctionFS at /dev/usb-ffs/NAME. Needs libcomposite and usb_f_fs loaded and
# configfs mounted at /sys/kernel/config.
set -eu
action=${1:-}
[ $# -gt 0 ] && shift
name=gabarit vid=0x1d6b pid=0x0104 serial="" ffs=""
while [ $# -gt 0 ]; do
  case "$1" in
    --name) name=$2; shift 2 ;;
    --vid) vid=$2; shift 2 ;;
    --pid) pid=$2; shift 2 ;;
    --serial) serial=$2; shift 2 ;;
    --ffs-dir) ffs=$2; shift 2 ;;
    *) echo "usb-gadget.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
[ -n "$ffs" ] || ffs=/dev/usb-ffs/$name
g=/sys/kernel/config/usb_gadget/$name
case "$action" in
  up)
    [ -d /sys/kernel/config/usb_gadget ] || { echo "usb-gadget.sh: no /sys/kernel/config/usb_gadget (configfs mounted? libcomposite loaded?)" >&2; exit 1; }
    if [ -z "$serial" ]; then serial=$(cut -c1-16 /etc/machine-id 2>/dev/null || echo 0); fi
    mkdir -p "$g"
    echo "$vid" > "$g/idVendor"
    echo "$pid" > "$g/idProduct"
    echo 0x0200 > "$g/bcdUSB"
    mkdir -p "$g/strings/0x409"
    echo "$serial" > "$g/strings/0x409/serialnumber"
    echo "gabarit" > "$g/strings/0x409/manufacturer"
    echo "gabarit HIL link" > "$g/strings/0x409/product"
    mkdir -p "$g/configs/c.1/strings/0x409"
    echo "HIL link" > "$g/configs/c.1/strings/0x409/configuration"
    echo 100 > "$g/configs/c.1/MaxPower"
    mkdir -p "$g/functions/ffs.$name"
    [ -e "$g/configs/c.1/ffs.$name" ] || ln -s "$g/functions/ffs.$name" "$g/configs/c.1/"
    mkdir -p "$ffs"
    grep -q " $ffs functionfs " /proc/mounts || mount -t functionfs "$name" "$ffs"
    echo "usb-gadget.sh: $g ($vid:$pid serial $serial), FunctionFS at $ffs"
    ;;
  down)
    [ -e "$g/UDC" ] && echo "" > "$g/UDC" 2>/dev/null || true
    grep -q " $ffs functionfs " /proc/mounts && umount "$ffs"
    rm -f "$g/configs/c.1/ffs.$name"
    rmdir "$g/configs/c.1/strings/0x409" "$g/configs/c.1" "$g/functions/ffs.$name" "$g/strings/0x409" "$g" 2>/dev/null || true
    ;;
  *) echo "usage: usb-gadget.sh up|down [options] (see the file's header)" >&2; exit 2 ;;
esac
