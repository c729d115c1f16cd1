#!/usr/bin/env bash
# Formal proofs of the hardware voter with Debian's yosys and yosys-smtbmc +
# z3 (--unroll: z3 is fast on the unrolled form). Each proof is BMC from reset
# for B clocks (the base case), then k-induction with depth K <= B, which
# together prove the properties for runs of any length.
#
#   fifo    gbt_fifo, the voter's 16-deep instance (FORMAL_FIFO block):
#           occupancy never above the depth; pushes minus pops equals the
#           occupancy (no word dropped or duplicated); words leave in order
#           (data-independence: each word is its push's sequence number).
#   lane    gbt_vote_lane alone (FORMAL_LANE: its environment assumed):
#           every counter read-modify-write sees the counter's current value,
#           so a counter never decreases and never wraps between clears;
#           refs, counter and size addresses stay in range; the FIFO's
#           invariants.
#   voter1, voter2
#           gbt_voter with 1 and 2 lanes: the lanes' environment is proved
#           (clear only while idle, no push into a full FIFO or while
#           clearing, ranges inside the refs memory), the lane properties
#           hold inside it, and every feature taken is counted once as
#           accepted, out of the ROI or over capacity (the handshake never
#           drops or duplicates one).
# Instances are small (3-5 cells, 4 pixels, 6-12 references); the logic does
# not depend on the sizes beyond address widths. Assumed throughout: a valid
# table (references name cells of their bank, ranges inside the refs
# memory) that is not rewritten mid-frame.
# usage: prove.sh fifo|lane|voter1|voter2 [WORKDIR]
set -euo pipefail
target=${1:?usage: prove.sh fifo|lane|voter1|voter2 [WORKDIR]}
here=$(cd "$(dirname "$0")" && pwd)
rtl=$here/../rtl
work=${2:-$(mktemp -d)}
mkdir -p "$work"
case $target in
  fifo)   defs="-D FORMAL_FIFO"; srcs="$rtl/gbt_fifo.sv"; top=gbt_fifo
          params="-set Depth 16 -set WidthBits 8"; bmc=6; k=4 ;;
  lane)   defs="-D FORMAL_LANE"; srcs="$rtl/gbt_pkg.sv $rtl/gbt_sync_ram.sv $rtl/gbt_fifo.sv $rtl/gbt_vote_lane.sv"; top=gbt_vote_lane
          params="-set CellsPerLane 5 -set RefsPerLane 12 -set FifoDepth 16"; bmc=8; k=6 ;;
  voter1|voter2)
          defs=""; srcs="$rtl/gbt_pkg.sv $rtl/gbt_sync_ram.sv $rtl/gbt_fifo.sv $rtl/gbt_mul_add.sv $rtl/gbt_vote_lane.sv $rtl/gbt_voter.sv"
          top=gbt_voter; lanes=${target#voter}; cells=$((lanes == 1 ? 3 : 5))
          params="-set Lanes $lanes -set CellCapacity $cells -set PixelCapacity 4 -set RefsPerLane 6 -set MaxFeaturesPerFrame 3 -set FifoDepth 16"
          bmc=12; k=8 ;;
  *) echo "unknown proof: $target" >&2; exit 2 ;;
esac
cat > "$work/$target.ys" <<YS
read_verilog -formal $defs -sv $srcs
chparam $params $top
prep -top $top
async2sync
dffunmap
write_smt2 -wires $work/$target.smt2
YS
yosys -q "$work/$target.ys" > "$work/yosys.log" 2>&1 || { cat "$work/yosys.log"; exit 1; }
status=0
for mode in "bmc:-t $bmc" "induction:-i -t $k"; do
  name=${mode%%:*}
  # shellcheck disable=SC2086  # the options are words
  if yosys-smtbmc -s z3 --unroll ${mode#*:} "$work/$target.smt2" > "$work/$target-$name.log" 2>&1 \
       && grep -q "Status: PASSED" "$work/$target-$name.log"; then
    echo "$top ($target) $name: PASSED"
  else
    echo "$top ($target) $name: FAILED"; tr '\r' '\n' < "$work/$target-$name.log" | grep -v '^ *(' | tail -n 20
    status=1
  fi
done
exit $status
