#!/usr/bin/env bash
# Synthesis and place-and-route report for the hardware voter.
#   hdl/synth/synth.sh TABLE.gbt OUTDIR [LANES...]
# For each lane count: `gabarit tables export-hdl`, yosys synth_ice40 (-dsp
# -spram: UltraPlus DSPs and SPRAM) and a generic `synth`, then nextpnr-ice40
# for the UP5K (sg48) with a 48 MHz target. Writes OUTDIR/report.md with LUTs,
# memory blocks, DSPs, Fmax and votes per second (lanes x Fmax).
# EXPORT_ARGS (optional): more `tables export-hdl` options, e.g. "--range-count 3"
# for narrow offsets words. SEEDS (default "1 2 3 4 5"): nextpnr placement
# seeds; the report gives the best build's Fmax and the range over the seeds
# (placement alone moves Fmax by about 10% on this design).
set -euo pipefail
table=${1:?usage: synth.sh TABLE.gbt OUTDIR [LANES...]}
out=${2:?usage: synth.sh TABLE.gbt OUTDIR [LANES...]}
shift 2
lanes_list=${*:-1 2 4}
here=$(cd "$(dirname "$0")" && pwd)
rtl=$here/../rtl
gabarit=${GABARIT:-$here/../../build/release/tools/gabarit}
mkdir -p "$out"
report=$out/report.md
{
  echo "# Hardware voter synthesis ($(date -u +%Y-%m-%d), $(yosys -V | cut -d' ' -f1-2), nextpnr-ice40)"
  echo
  "$gabarit" tables inspect "$table" > "$out/table.json"
  python3 - "$out/table.json" "$table" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
print(f"Table: `{sys.argv[2]}`: {d['cells']} cells, ROI {d['roi']['width']}x{d['roi']['height']}, {d['references']} references.")
PY
  echo "Target: iCE40 UP5K (5280 LUT4, 30 EBR of 4 kbit, 4 SPRAM of 256 kbit, 8 DSP), table loaded at boot through the table port (SPRAM cannot be preloaded)."
  echo
  echo "| lanes | LUT4 | carry | DFF | EBR | SPRAM | DSP | generic (coarse) cells | fits UP5K | Fmax (MHz), best seed | Fmax over seeds | votes/s |"
  echo "|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---|---:|"
} > "$report"
for lanes in $lanes_list; do
  d=$out/lanes$lanes
  mkdir -p "$d"
  # shellcheck disable=SC2086  # EXPORT_ARGS is words, e.g. "--range-count 3"
  "$gabarit" tables export-hdl "$table" --out "$d/table" --lanes "$lanes" ${EXPORT_ARGS:-} 2>>"$d/export.log"
  srcs="$d/table/gabarit_table_pkg.sv $rtl/gbt_pkg.sv $rtl/gbt_sync_ram.sv $rtl/gbt_fifo.sv $rtl/gbt_mul_add.sv $rtl/gbt_vote_lane.sv $rtl/gbt_voter.sv $rtl/gbt_voter_table.sv $here/gbt_synth_top.sv"
  # -noassert: the RTL's assertions are for simulation and formal, not silicon.
  yosys -q -l "$d/yosys_ice40.log" -p "read_verilog -sv -noassert $srcs; synth_ice40 -top gbt_synth_top -dsp -spram -json $d/voter.json; tee -o $d/ice40_stat.txt stat" >/dev/null
  # Generic flow, stopped before fine-grain mapping: memories stay memory cells.
  yosys -q -l "$d/yosys_generic.log" -p "read_verilog -sv -noassert $srcs; synth -top gbt_synth_top -run begin:fine; tee -o $d/generic_stat.txt stat" >/dev/null
  count() { grep -E "^\s+$1\s" "$d/ice40_stat.txt" | tail -1 | awk '{print $2}' || true; }
  lut=$(count SB_LUT4); carry=$(count SB_CARRY); ebr=$(count SB_RAM40_4K); spram=$(count SB_SPRAM256KA); dsp=$(count SB_MAC16)
  dff=$(grep -E "^\s+SB_DFF" "$d/ice40_stat.txt" | awk '{s+=$2} END {print s+0}')
  generic=$(grep -E "Number of cells:" "$d/generic_stat.txt" | tail -1 | awk '{print $4}')
  fits=yes fmax=- vps=- spread=-
  best_seed=
  for seed in ${SEEDS:-1 2 3 4 5}; do
    if nextpnr-ice40 --up5k --package sg48 --json "$d/voter.json" --freq 48 --seed "$seed" --timing-allow-fail \
         --report "$d/nextpnr-$seed.json" >"$d/nextpnr-$seed.log" 2>&1; then
      python3 - "$d/nextpnr-$seed.json" > "$d/fmax-$seed.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print(f"{min(v['achieved'] for v in r['fmax'].values()):.1f}")
PY
      f=$(cat "$d/fmax-$seed.txt")
      if [ -z "$best_seed" ] || python3 -c "import sys; sys.exit(0 if $f > $fmax else 1)"; then fmax=$f; best_seed=$seed; fi
    else
      fits="no ($(grep -m1 -E 'ERROR' "$d/nextpnr-$seed.log" | cut -c1-80))"
      break
    fi
  done
  if [ -n "$best_seed" ] && [ "$fits" = yes ]; then
    cp "$d/nextpnr-$best_seed.log" "$d/nextpnr.log"
    spread="$(sort -n "$d"/fmax-*.txt | head -1)-$(sort -n "$d"/fmax-*.txt | tail -1) (seeds ${SEEDS:-1 2 3 4 5})"
    vps=$(python3 -c "print(f'{$lanes * $fmax * 1e6:.3g}')")
    fmax="$fmax (seed $best_seed)"
  fi
  echo "| $lanes | ${lut:-0} | ${carry:-0} | ${dff:-0} | ${ebr:-0} | ${spram:-0} | ${dsp:-0} | ${generic:-?} | $fits | $fmax | $spread | $vps |" >> "$report"
  echo "lanes $lanes: LUT ${lut:-0}, EBR ${ebr:-0}, SPRAM ${spram:-0}, DSP ${dsp:-0}, Fmax $fmax MHz" >&2
done
echo >> "$report"
echo "Memory of each configuration: see lanes*/table/gabarit_table_pkg.sv (MemoryBits). Logs: lanes*/*.log." >> "$report"
cat "$report"
