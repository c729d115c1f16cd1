#!/bin/busybox sh
# /init of the virtual board (busybox, Debian's arm64 kernel under QEMU). It
# loads the drivers, runs the board application against vivid and gpio-sim,
# prints the poses between markers for the host to compare, and ends with one
# line "VIRTUAL-BOARD: PASS" or "VIRTUAL-BOARD: FAIL <reasons>" (QEMU exits 0
# whatever happens here). Inputs are in /data (see run.sh).
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mkdir -p /tmp && mount -t tmpfs tmp /tmp
. /data/params.sh  # INIT, SIZE, HOLD_MS, FRAMES

failures=""
fail() { failures="$failures [$1]"; echo "virtual-board: FAILED: $1"; }
finish() {
  if [ -z "$failures" ]; then echo "VIRTUAL-BOARD: PASS"; else echo "VIRTUAL-BOARD: FAIL$failures"; fi
  sync
  poweroff -f
}

load_modules() {
  while read -r ko; do
    case "$ko" in
      */vivid.ko) insmod "/modules/$(basename "$ko")" node_types=0x101 n_devs=1 || return 1 ;;
      *) insmod "/modules/$(basename "$ko")" || return 1 ;;
    esac
  done < /modules/order
}
load_modules || { fail "loading modules"; finish; }
mount -t configfs none /sys/kernel/config || { fail "configfs"; finish; }
for i in 1 2 3 4 5 6 7 8 9 10; do [ -e /dev/video1 ] && break; sleep 0.2; done
[ -e /dev/video0 ] && [ -e /dev/video1 ] || { fail "vivid created no /dev/video0 and /dev/video1"; finish; }

# gpio-sim: one bank of 3 lines. 0 = lock (output), 1 = strobe (output), 2 = trigger (input).
cfg=/sys/kernel/config/gpio-sim/board
mkdir $cfg $cfg/bank0 && echo 3 > $cfg/bank0/num_lines && echo 1 > $cfg/live || { fail "gpio-sim configuration"; finish; }
chip=$(cat $cfg/bank0/chip_name)
sim=/sys/devices/platform/$(cat $cfg/dev_name)/$chip
echo "virtual-board: gpio-sim chip $chip"
line_value() { cat $sim/sim_gpio$1/value; }

# Samples the lock and strobe lines until /tmp/stop-sampling appears:
# counts strobe rising edges and whether lock was ever high. Shell builtins
# only (no fork per sample), so a sample takes well under a millisecond.
sample_lines() {
  rising=0; last=0; lock_high=0; samples=0
  while [ ! -e /tmp/stop-sampling ]; do
    read -r s < $sim/sim_gpio1/value
    [ "$s" = 1 ] && [ "$last" = 0 ] && rising=$((rising + 1))
    last=$s
    read -r l < $sim/sim_gpio0/value
    [ "$l" = 1 ] && lock_high=1
    samples=$((samples + 1))
  done
  echo "$rising $lock_high $samples" > /tmp/sampled
}

board_args="--device /dev/video0 --format GREY --table /data/table.gbt --init $INIT --binary --frame-crc"

# 1. Track the recording through vivid, with the lock and strobe lines.
gabarit-vivid-feed setup --capture /dev/video0 --output /dev/video1 --size "$SIZE" || fail "vivid setup"
gabarit-vivid-feed play --output /dev/video1 --frames /data/frames.y4m --hold-ms "$HOLD_MS" --first-hold-ms 3000 \
  2> /tmp/feed.log &
feed=$!
sleep 1
sample_lines &
sampler=$!
gabarit-board $board_args --gpio-chip "$chip" --lock-line 0 --strobe-line 1 --strobe-us 8000 \
  > /tmp/poses.csv 2> /tmp/board.log &
board=$!
# Captured buffers come back flagged V4L2_BUF_FLAG_ERROR: skipped, counted.
# (vivid loses about one injection in three, apparently when its next tick
# finds no queued capture buffer; ten are made and at least one must arrive.)
sleep 1
for i in 1 2 3 4 5 6 7 8 9 10; do
  gabarit-vivid-feed error --capture /dev/video0 || fail "vivid error injection"
  sleep 0.15
done
wait $feed || fail "feeding frames"
sleep 0.3
kill -TERM $board
wait $board || fail "gabarit-board exit status $? after SIGTERM"
touch /tmp/stop-sampling
wait $sampler
cat /tmp/feed.log /tmp/board.log
echo "=== poses ==="
cat /tmp/poses.csv
echo "=== end poses ==="
tracked=$(($(wc -l < /tmp/poses.csv) - 1))
read rising lock_high samples < /tmp/sampled
echo "virtual-board: $tracked frames tracked, $rising strobe pulses seen in $samples samples, lock high seen: $lock_high"
[ "$tracked" -ge "$FRAMES" ] || fail "only $tracked frames tracked"
grep -Eq " ([1-9]|10) flagged bad" /tmp/board.log || fail "no error-flagged buffer was skipped and counted"
# A polled shell sees nearly every 8 ms pulse; demand 90% of the frames.
[ $((rising * 10)) -ge $((tracked * 9)) ] && [ "$rising" -le "$tracked" ] || fail "strobe: $rising pulses for $tracked frames"
[ "$lock_high" = 1 ] || fail "lock never went high while tracking"
[ "$(line_value 0)" = 0 ] && [ "$(line_value 1)" = 0 ] || fail "GPIO outputs not low after exit"

# 2. Trigger: started stopped, nothing is tracked until a rising edge on line 2.
echo pull-down > $sim/sim_gpio2/pull
rm -f /tmp/stop-sampling
gabarit-vivid-feed setup --capture /dev/video0 --output /dev/video1 --size "$SIZE" || fail "vivid setup (trigger)"
gabarit-vivid-feed play --output /dev/video1 --frames /data/frames.y4m --hold-ms 100 2> /dev/null &
feed=$!
gabarit-board $board_args --gpio-chip "$chip" --trigger-line 2 --start-stopped > /tmp/trigger.csv 2> /tmp/trigger.log &
board=$!
sleep 1.5
before=$(($(wc -l < /tmp/trigger.csv) - 1))
echo pull-up > $sim/sim_gpio2/pull
sleep 1.5
after=$(($(wc -l < /tmp/trigger.csv) - 1))
kill -TERM $board; wait $board
wait $feed
echo "virtual-board: trigger: $before frames tracked before the edge, $after after"
[ "$before" = 0 ] && [ "$after" -gt 0 ] || fail "trigger: $before before, $after after the edge"
grep -q "tracking started" /tmp/trigger.log || fail "trigger: no 'tracking started' report"

# 3. Unplug: vivid disconnects, its module is unloaded and loaded again.
# After the loss the board waits 1 s before reopening: time to unload the module.
gabarit-board --device /dev/video0 --format GREY --table /data/table.gbt --init $INIT --binary \
  --reopen-min-ms 1000 --reopen-max-ms 1000 > /tmp/unplug.csv 2> /tmp/unplug.log &
board=$!
sleep 1.5
gabarit-vivid-feed disconnect --capture /dev/video0 || fail "vivid disconnect"
i=0
while [ $i -lt 40 ] && ! rmmod vivid 2>/dev/null; do sleep 0.05; i=$((i + 1)); done
lsmod | grep -q '^vivid' && fail "vivid could not be unloaded (device still held open?)"
sleep 1.5
kill -0 $board 2>/dev/null || fail "gabarit-board died when the camera went away"
insmod /modules/vivid.ko node_types=0x101 n_devs=1 || fail "reloading vivid"
lines_replugged=$(wc -l < /tmp/unplug.csv)
sleep 2.5
lines_end=$(wc -l < /tmp/unplug.csv)
kill -TERM $board; wait $board || fail "gabarit-board exit status after the unplug test"
cat /tmp/unplug.log
grep -q "lost /dev/video0" /tmp/unplug.log || fail "unplug not reported"
[ "$lines_end" -gt "$lines_replugged" ] || fail "no frames tracked after the camera came back"
finish
