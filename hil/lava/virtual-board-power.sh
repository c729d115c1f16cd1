#!/usr/bin/env bash
# The aarch64 virtual board's power, for a LAVA device of type gabarit-board
# (docs/hil-farm.md), as a lab's PDU script is a real board's:
#   virtual-board-power.sh on STATE -- COMMAND...   powers it on: COMMAND (the
#       virtual board's serve.sh with its options) in a session of its own,
#       in the background; the output in STATE/serve.log
#   virtual-board-power.sh off STATE                powers it off, if it is on
# STATE is a folder of the device's own (its process id).
set -euo pipefail
action=${1:?usage: virtual-board-power.sh on STATE -- COMMAND... | off STATE}
state=${2:?usage: virtual-board-power.sh on STATE -- COMMAND... | off STATE}
shift 2
mkdir -p "$state"
power_off() {
  [ -f "$state/pid" ] || return 0
  kill -- -"$(cat "$state/pid")" 2> /dev/null || true
  rm -f "$state/pid"
}
case "$action" in
  off) power_off ;;
  on)
    power_off
    [ "${1:-}" = -- ] && shift
    [ $# -gt 0 ] || { echo "virtual-board-power.sh on: no command" >&2; exit 2; }
    # setsid: a session (and process group) of its own, which `off` ends
    # whole. LAVA runs this command on a pty and hangs it up as soon as this
    # script exits, perhaps before the child has left it: SIGHUP ignored.
    trap '' HUP
    setsid "$@" < /dev/null > "$state/serve.log" 2>&1 &
    echo $! > "$state/pid" ;;
  *) echo "virtual-board-power.sh: want on or off, not $action" >&2; exit 2 ;;
esac
