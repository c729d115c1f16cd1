#!/usr/bin/env bash
# Formal proof of the voter's intake FIFO (hdl/rtl/gbt_fifo.sv, its
# `ifdef FORMAL` block) with Debian's yosys and yosys-smtbmc + z3:
#   - BMC for 10 clocks (every reachable state, pointers wrapping), then
#   - k-induction with k = 4, which with the 4-clock base case is a proof for
#     runs of any length.
# Properties: occupancy never above the depth; pushes minus pops equals the
# occupancy (no word dropped or duplicated); every word leaves in the order it
# came in (data-independence: each word is its push's sequence number).
# Instance: Depth 4, 6-bit words (the voter's FIFO is 16 deep; a 16-deep
# instance is beyond z3's patience here, and the logic does not depend on the
# depth beyond pointer widths).
# usage: fifo.sh [WORKDIR]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
work=${1:-$(mktemp -d)}
mkdir -p "$work"
cat > "$work/fifo.ys" <<YS
read_verilog -formal -sv $here/../rtl/gbt_fifo.sv
chparam -set Depth 4 -set WidthBits 6 gbt_fifo
prep -top gbt_fifo
async2sync
dffunmap
write_smt2 -wires $work/fifo.smt2
YS
yosys -q "$work/fifo.ys" > "$work/yosys.log" 2>&1 || { cat "$work/yosys.log"; exit 1; }
status=0
for mode in "bmc:-t 10" "induction:-i -t 4"; do
  name=${mode%%:*}
  # shellcheck disable=SC2086  # the options are words
  if yosys-smtbmc -s z3 ${mode#*:} "$work/fifo.smt2" > "$work/$name.log" 2>&1 && grep -q "Status: PASSED" "$work/$name.log"; then
    echo "gbt_fifo $name: PASSED"
  else
    echo "gbt_fifo $name: FAILED"; tr '\r' '\n' < "$work/$name.log" | grep -v '^ *(' | tail -n 20
    status=1
  fi
done
exit $status
