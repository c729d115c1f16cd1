#!/bin/busybox sh
# /init of the virtual board as a HIL DUT (`gabarit hil run --dut virtual-board`):
# loads the drivers, makes the gpio-sim lines and the USB gadget as a board's
# own start-up would, then runs gabarit-hil-relay, which starts the board
# application and bridges the harness (the virtio-serial port gabarit.hil) to
# it through vivid and USB. Inputs in /data (hil-initramfs.sh). The console
# is the harness's dut.log; the last line is "VIRTUAL-BOARD: HIL DONE <status>".
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mkdir -p /tmp && mount -t tmpfs tmp /tmp
. /data/params.sh  # WINDOW, SERIAL, and PROFILE when the harness gave one
fail() {
  echo "virtual-board: FAILED: $1"
  echo "VIRTUAL-BOARD: HIL DONE 1"
  poweroff -f
}
while read -r ko; do
  case "$ko" in
    */vivid.ko) insmod "/modules/$(basename "$ko")" node_types=0x101 n_devs=1 || fail "insmod vivid" ;;
    *) insmod "/modules/$(basename "$ko")" || fail "insmod $ko" ;;
  esac
done < /modules/order
mount -t configfs none /sys/kernel/config || fail "configfs"
for i in 1 2 3 4 5 6 7 8 9 10; do [ -e /dev/video1 ] && break; sleep 0.2; done
[ -e /dev/video1 ] || fail "vivid created no /dev/video1"

# GPIO: 0 = lock, 1 = strobe (outputs, pulled down: low whenever no program drives them).
cfg=/sys/kernel/config/gpio-sim/board
mkdir $cfg $cfg/bank0 && echo 3 > $cfg/bank0/num_lines && echo 1 > $cfg/live || fail "gpio-sim"
chip=$(cat $cfg/bank0/chip_name)
sim=/sys/devices/platform/$(cat $cfg/dev_name)/$chip
for line in 0 1; do echo pull-down > $sim/sim_gpio$line/pull; done

sh /bin/usb-gadget.sh up --serial "$SERIAL" || fail "USB gadget"
ls /sys/class/udc > /dev/null || fail "no USB device controller (dummy_hcd)"

echo "virtual-board: starting the HIL relay"
gabarit-hil-relay --gpio-dir "$sim" --usb "0x1d6b:0x0104:$SERIAL" --board-log /tmp/board.log --table /data/table.gbt -- \
  /bin/gabarit-board --device /tmp/camera --format GREY --table /data/table.gbt --link usb \
  --usb-ffs /dev/usb-ffs/gabarit --usb-gadget /sys/kernel/config/usb_gadget/gabarit \
  --window "$WINDOW" --skip-repeats --gpio-chip "$chip" --lock-line 0 --strobe-line 1 --strobe-us 2000 \
  --reopen-min-ms 200 --reopen-max-ms 400 --frame-timeout-ms 1000 ${PROFILE:+--profile "$PROFILE"}
status=$?
if [ $status != 0 ]; then
  echo "=== the USB side: UDC '$(cat /sys/kernel/config/usb_gadget/gabarit/UDC)', controllers: $(ls /sys/class/udc), devices: $(ls /sys/bus/usb/devices)"
  dmesg | tail -n 15
fi
echo "=== board log (last 40 lines) ==="
tail -n 40 /tmp/board.log
echo "VIRTUAL-BOARD: HIL DONE $status"
sync
poweroff -f
