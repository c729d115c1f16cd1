// gbt_vote_lane — one voting lane: the counters of one bank of cells
// (cells c with c % Lanes == LaneIndex, at local address c / Lanes).
//
// Pipeline (one vote per clock in steady state; no stall, whatever the cells):
//
//   G   range generator: pops {begin, count} ranges from the FIFO and issues
//       one reference address per clock; the next range is loaded in the
//       cycle of the last reference, so back-to-back ranges have no bubble.
//   S2  refs RAM data = local cell index; issue counter and size reads.
//   S3  counter data; forwarding: if the previous vote (now in S4) hit the
//       same counter, its new value replaces the RAM word (the RAM is
//       read-first, so a read in the cycle of that write returned the old
//       word; a write lands before the read one cycle later, so one-deep
//       forwarding is enough). new = old + 1, saturating at 2^16 - 1 like the
//       kernel; written back in this cycle.
//   S4, S5 the bank's top-2 (best, runner-up) updated with the new count, in
//       two pipelined steps (see below). Counts only grow within a frame, so
//       the incremental top-2 is exact: a cell that overtakes the best pushes
//       it to runner-up; one that overtakes the runner-up replaces it.
//
// Latency from FIFO push to top-2 update: 5 clocks for a range's first vote.
// Clearing (clear_i) sweeps the bank's counters, one per clock
// (CellsPerLane clocks), and resets the top-2 to the bank's two lowest cells
// with zero votes — exactly where the kernel's ranking starts.
`default_nettype none

module gbt_vote_lane #(
  parameter int unsigned Lanes = 1,
  parameter int unsigned LaneIndex = 0,
  parameter int unsigned CellsPerLane = 121,
  parameter int unsigned RefsPerLane = 1024,
  parameter int unsigned FifoDepth = 16,
  parameter RefsInitFile = "",   // strings (untyped for yosys 0.23)
  parameter SizesInitFile = "",
  localparam int unsigned LocalCellWidth = (CellsPerLane > 1) ? $clog2(CellsPerLane) : 1,
  localparam int unsigned RefAddrWidth = (RefsPerLane > 1) ? $clog2(RefsPerLane) : 1,
  localparam int unsigned OffsetWidth = $clog2(RefsPerLane + 1),
  localparam int unsigned RangeCountWidth = $clog2(CellsPerLane + 1),
  localparam int unsigned FreeWidth = $clog2(FifoDepth) + 1
) (
  input  logic clk_i,
  input  logic rst_ni,

  input  logic clear_i,            // start the counter sweep (pipeline must be idle)
  input  logic [31:0] cell_count_i, // cells of the loaded table (all banks)
  output logic idle_o,             // nothing queued, in flight or clearing

  input  logic                       range_push_i,
  input  logic [OffsetWidth-1:0]     range_begin_i,
  input  logic [RangeCountWidth-1:0] range_count_i,  // >= 1
  output logic [FreeWidth-1:0]       range_free_o,

  output logic        best_valid_o,
  output logic [31:0] best_cell_o,
  output gbt_pkg::count_t      best_votes_o,
  output gbt_pkg::size_t       best_size_o,
  output logic        runner_valid_o,
  output logic [31:0] runner_cell_o,
  output gbt_pkg::count_t      runner_votes_o,
  output gbt_pkg::size_t       runner_size_o,
  output logic [31:0] votes_o,     // counter increments since the last clear

  input  logic                      tbl_refs_we_i,
  input  logic                      tbl_sizes_we_i,
  // A 32-bit table bus shared by every memory; each takes the bits it needs.
  /* verilator lint_off UNUSEDSIGNAL */
  input  logic [31:0]               tbl_addr_i,
  input  logic [31:0]               tbl_data_i,
  /* verilator lint_on UNUSEDSIGNAL */

  input  logic [LocalCellWidth-1:0] cnt_raddr_i,  // readback while idle
  output gbt_pkg::count_t                    cnt_rdata_o   // one clock later
);

  // Package items are named in full: yosys 0.23 reads no `import` in a module.

  // ---------------------------------------------------------------- ranges
  logic [OffsetWidth-1:0]     head_begin;
  logic [RangeCountWidth-1:0] head_count;
  logic fifo_empty, fifo_full, pop;

  gbt_fifo #(.Depth(FifoDepth), .WidthBits(OffsetWidth + RangeCountWidth)) u_fifo (
    .clk_i, .rst_ni,
    .push_i(range_push_i), .wdata_i({range_begin_i, range_count_i}),
    .pop_i(pop), .rdata_o({head_begin, head_count}),
    .empty_o(fifo_empty), .full_o(fifo_full), .free_o(range_free_o)
  );

  // ------------------------------------------------------------- generator
  logic                       gen_active_q;
  logic [OffsetWidth-1:0]     gen_addr_q;
  logic [RangeCountWidth-1:0] gen_left_q;
  wire last_ref = gen_active_q && (gen_left_q == RangeCountWidth'(1));
  assign pop = !fifo_empty && (!gen_active_q || last_ref);

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      gen_active_q <= 1'b0;
      gen_addr_q <= '0;
      gen_left_q <= '0;
    end else if (pop) begin
      gen_active_q <= 1'b1;
      gen_addr_q <= head_begin;
      gen_left_q <= head_count;
    end else if (gen_active_q) begin
      gen_active_q <= !last_ref;
      gen_addr_q <= gen_addr_q + 1'b1;
      gen_left_q <= gen_left_q - 1'b1;
    end
  end

  // -------------------------------------------------------------- S2: refs
  logic [LocalCellWidth-1:0] s2_cell;
  logic s2_valid_q;
  gbt_sync_ram #(.Depth(RefsPerLane), .WidthBits(LocalCellWidth), .InitFile(RefsInitFile), .SinglePort(1'b1)) u_refs (
    .clk_i, .raddr_i(gen_addr_q[RefAddrWidth-1:0]), .rdata_o(s2_cell),
    .we_i(tbl_refs_we_i), .waddr_i(tbl_addr_i[RefAddrWidth-1:0]), .wdata_i(tbl_data_i[LocalCellWidth-1:0])
  );

  // ------------------------------------------------- S3: counters and sizes
  logic                      s3_valid_q, s4_valid_q;
  logic [LocalCellWidth-1:0] s3_cell_q, s4_cell_q;
  gbt_pkg::count_t                    s4_votes_q;
  gbt_pkg::size_t                     s4_size_q;
  gbt_pkg::count_t                    cnt_rdata, s3_old, s3_new;
  gbt_pkg::size_t                     size_rdata;

  logic                      clearing_q;
  logic [LocalCellWidth-1:0] clear_addr_q;

  logic                      cnt_we;
  logic [LocalCellWidth-1:0] cnt_waddr, cnt_raddr;
  gbt_pkg::count_t                    cnt_wdata;

  assign cnt_raddr = s2_valid_q ? s2_cell : cnt_raddr_i;
  assign cnt_we    = clearing_q || s3_valid_q;
  assign cnt_waddr = clearing_q ? clear_addr_q : s3_cell_q;
  assign cnt_wdata = clearing_q ? '0 : s3_new;

  gbt_sync_ram #(.Depth(CellsPerLane), .WidthBits(gbt_pkg::CounterWidthBits)) u_counters (
    .clk_i, .raddr_i(cnt_raddr), .rdata_o(cnt_rdata),
    .we_i(cnt_we), .waddr_i(cnt_waddr), .wdata_i(cnt_wdata)
  );
  gbt_sync_ram #(.Depth(CellsPerLane), .WidthBits(gbt_pkg::SizeWidthBits), .InitFile(SizesInitFile), .SinglePort(1'b1)) u_sizes (
    .clk_i, .raddr_i(s2_cell), .rdata_o(size_rdata),
    .we_i(tbl_sizes_we_i), .waddr_i(tbl_addr_i[LocalCellWidth-1:0]), .wdata_i(tbl_data_i[gbt_pkg::SizeWidthBits-1:0])
  );
  assign cnt_rdata_o = cnt_rdata;

  assign s3_old = (s4_valid_q && s4_cell_q == s3_cell_q) ? s4_votes_q : cnt_rdata;
  assign s3_new = (s3_old == '1) ? s3_old : s3_old + 1'b1;

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      s2_valid_q <= 1'b0;
      s3_valid_q <= 1'b0;
      s4_valid_q <= 1'b0;
      s3_cell_q <= '0;
      s4_cell_q <= '0;
      s4_votes_q <= '0;
      s4_size_q <= '0;
    end else begin
      s2_valid_q <= gen_active_q;
      s3_valid_q <= s2_valid_q;
      s3_cell_q <= s2_cell;
      s4_valid_q <= s3_valid_q;
      s4_cell_q <= s3_cell_q;
      s4_votes_q <= s3_new;
      s4_size_q <= size_rdata;
    end
  end

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      clearing_q <= 1'b0;
      clear_addr_q <= '0;
    end else if (clear_i) begin
      clearing_q <= 1'b1;
      clear_addr_q <= '0;
    end else if (clearing_q) begin
      clearing_q <= 32'(clear_addr_q) != CellsPerLane - 1;
      clear_addr_q <= clear_addr_q + 1'b1;
    end
  end

  // ------------------------------------------------- S4, S5: top-2, pipelined
  // The top-2 lives in local cell indices: within a bank, c / Lanes orders
  // cells exactly as c does, and the comparisons stay narrow.
  //   S4 (stage A): the new count x is compared with the bank's best and
  //     runner-up as they stand now, and with y, the count in S5 whose update
  //     lands at the end of this clock (three cross-multiplications).
  //   S5 (stage B): y's update has landed. It can only have put y into best
  //     or runner-up, or moved the old best down to runner-up, so x's
  //     comparison with the current best and runner-up is one of the three
  //     computed in S4, picked by cell identity. Then the update rules.
  // Exact whatever the sequence of cells, and no comparison longer than one
  // clock. Latency from S3: 2 clocks.
  logic                      best_valid_q, runner_valid_q;
  logic [LocalCellWidth-1:0] best_cell_q, runner_cell_q;
  gbt_pkg::count_t           best_votes_q, runner_votes_q;
  gbt_pkg::size_t            best_size_q, runner_size_q;
  logic [31:0]               votes_q;

  logic                      s5_valid_q, s5_beats_best_q, s5_beats_runner_q, s5_beats_prev_q;
  logic [LocalCellWidth-1:0] s5_cell_q, s5_old_best_q;
  gbt_pkg::count_t           s5_votes_q;
  gbt_pkg::size_t            s5_size_q;

  // Stage A (S4).
  wire a_beats_best = !best_valid_q ||
      gbt_pkg::ranks_before(32'(s4_cell_q), s4_votes_q, s4_size_q, 32'(best_cell_q), best_votes_q, best_size_q);
  wire a_beats_runner = !runner_valid_q ||
      gbt_pkg::ranks_before(32'(s4_cell_q), s4_votes_q, s4_size_q, 32'(runner_cell_q), runner_votes_q, runner_size_q);
  wire a_beats_prev =
      gbt_pkg::ranks_before(32'(s4_cell_q), s4_votes_q, s4_size_q, 32'(s5_cell_q), s5_votes_q, s5_size_q);

  // Stage B (S5): which comparison describes the current best and runner-up.
  logic                      prev_valid_q;  // s5 one clock ago was a vote (y)
  logic [LocalCellWidth-1:0] prev_cell_q;
  wire best_is_prev   = prev_valid_q && best_valid_q && best_cell_q == prev_cell_q;
  wire runner_is_prev = prev_valid_q && runner_valid_q && runner_cell_q == prev_cell_q;
  wire runner_is_old_best = runner_valid_q && runner_cell_q == s5_old_best_q;
  wire x_beats_best   = best_is_prev ? s5_beats_prev_q : s5_beats_best_q;
  wire x_beats_runner = runner_is_prev ? s5_beats_prev_q : (runner_is_old_best ? s5_beats_best_q : s5_beats_runner_q);

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      s5_valid_q <= 1'b0;
      s5_beats_best_q <= 1'b0;
      s5_beats_runner_q <= 1'b0;
      s5_beats_prev_q <= 1'b0;
      s5_cell_q <= '0;
      s5_old_best_q <= '0;
      s5_votes_q <= '0;
      s5_size_q <= '0;
      prev_valid_q <= 1'b0;
      prev_cell_q <= '0;
    end else begin
      s5_valid_q <= s4_valid_q;
      s5_beats_best_q <= a_beats_best;
      s5_beats_runner_q <= a_beats_runner;
      s5_beats_prev_q <= s5_valid_q && a_beats_prev;
      s5_cell_q <= s4_cell_q;
      s5_old_best_q <= best_cell_q;
      s5_votes_q <= s4_votes_q;
      s5_size_q <= s4_size_q;
      prev_valid_q <= s5_valid_q;
      prev_cell_q <= s5_cell_q;
    end
  end

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      best_valid_q <= 1'b0;
      runner_valid_q <= 1'b0;
      best_cell_q <= '0;
      runner_cell_q <= '0;
      best_votes_q <= '0;
      runner_votes_q <= '0;
      best_size_q <= '0;
      runner_size_q <= '0;
      votes_q <= '0;
    end else if (clear_i) begin
      // Zero votes everywhere: the kernel's order is then the cell index.
      best_valid_q <= LaneIndex < cell_count_i;
      best_cell_q <= '0;
      best_votes_q <= '0;
      best_size_q <= gbt_pkg::SizeWidthBits'(1);
      runner_valid_q <= LaneIndex + Lanes < cell_count_i;
      runner_cell_q <= LocalCellWidth'(1);
      runner_votes_q <= '0;
      runner_size_q <= gbt_pkg::SizeWidthBits'(1);
      votes_q <= '0;
    end else begin
      if (s3_valid_q) votes_q <= votes_q + 1;
      if (s5_valid_q) begin
        if (best_valid_q && s5_cell_q == best_cell_q) begin
          best_votes_q <= s5_votes_q;
          best_size_q <= s5_size_q;
        end else if (x_beats_best) begin
          runner_valid_q <= best_valid_q;
          runner_cell_q <= best_cell_q;
          runner_votes_q <= best_votes_q;
          runner_size_q <= best_size_q;
          best_valid_q <= 1'b1;
          best_cell_q <= s5_cell_q;
          best_votes_q <= s5_votes_q;
          best_size_q <= s5_size_q;
        end else if ((runner_valid_q && s5_cell_q == runner_cell_q) || !runner_valid_q || x_beats_runner) begin
          runner_valid_q <= 1'b1;
          runner_cell_q <= s5_cell_q;
          runner_votes_q <= s5_votes_q;
          runner_size_q <= s5_size_q;
        end
      end
    end
  end

  assign best_valid_o = best_valid_q;
  assign best_cell_o = 32'(best_cell_q) * Lanes + LaneIndex;
  assign best_votes_o = best_votes_q;
  assign best_size_o = best_size_q;
  assign runner_valid_o = runner_valid_q;
  assign runner_cell_o = 32'(runner_cell_q) * Lanes + LaneIndex;
  assign runner_votes_o = runner_votes_q;
  assign runner_size_o = runner_size_q;
  assign votes_o = votes_q;
  assign idle_o = fifo_empty && !gen_active_q && !s2_valid_q && !s3_valid_q && !s4_valid_q && !s5_valid_q && !clearing_q;

  // Checked in simulation (Verilator --assert) on every clock of the co-simulation:
  // counters never wrap and never decrease within a frame — each write is the
  // value read plus one, or the saturated maximum; addresses stay in range;
  // the intake's slack rule never pushes into a full FIFO.
  // Assertions look at rst_ni only to stay quiet during reset; no logic is
  // built from that synchronous use.
  /* verilator lint_off SYNCASYNCNET */
  always_ff @(posedge clk_i) begin
    if (rst_ni && s3_valid_q && !clearing_q) begin
      CounterIncrements: assert (s3_new == s3_old + 1'b1 || (s3_old == '1 && s3_new == '1));
      CellInRange: assert (32'(s3_cell_q) < CellsPerLane);
    end
    if (rst_ni && range_push_i) NoPushWhenFull: assert (!fifo_full);
  end
  /* verilator lint_on SYNCASYNCNET */

endmodule

`default_nettype wire
