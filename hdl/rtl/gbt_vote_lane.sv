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
//   S4-S6 the bank's top-2 (best, runner-up) updated with the new count, in
//       three pipelined steps: products, comparisons, update (see below).
//       Counts only grow within a frame, so the incremental top-2 is exact.
//
// Latency from FIFO push to top-2 update: 6 clocks for a range's first vote.
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
  parameter int unsigned MaxRangeCount = 0,  // longest range pushed; 0 = CellsPerLane
  parameter RefsInitFile = "",   // strings (untyped for yosys 0.23)
  parameter SizesInitFile = "",
  localparam int unsigned LocalCellWidth = (CellsPerLane > 1) ? $clog2(CellsPerLane) : 1,
  localparam int unsigned RefAddrWidth = (RefsPerLane > 1) ? $clog2(RefsPerLane) : 1,
  localparam int unsigned OffsetWidth = $clog2(RefsPerLane + 1),
  localparam int unsigned RangeCountWidth = $clog2(((MaxRangeCount == 0) ? CellsPerLane : MaxRangeCount) + 1),
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
  logic                       gen_last_q;  // gen_left_q == 1, kept as a flag so pop is shallow
  wire last_ref = gen_active_q && gen_last_q;
  assign pop = !fifo_empty && (!gen_active_q || last_ref);

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      gen_active_q <= 1'b0;
      gen_addr_q <= '0;
      gen_left_q <= '0;
      gen_last_q <= 1'b0;
    end else if (pop) begin
      gen_active_q <= 1'b1;
      gen_addr_q <= head_begin;
      gen_left_q <= head_count;
      gen_last_q <= head_count == RangeCountWidth'(1);
    end else if (gen_active_q) begin
      gen_active_q <= !last_ref;
      // Held on the last reference, so the refs address stays in range.
      if (!last_ref) gen_addr_q <= gen_addr_q + 1'b1;
      gen_left_q <= gen_left_q - 1'b1;
      gen_last_q <= gen_left_q == RangeCountWidth'(2);
    end
  end

  // -------------------------------------------------------------- S2: refs
  logic [LocalCellWidth-1:0] s2_cell;
  logic s2_valid_q;
  gbt_sync_ram #(.Depth(RefsPerLane), .WidthBits(LocalCellWidth), .InitFile(RefsInitFile), .SinglePort(1'b1)) u_refs (
    .clk_i, .raddr_i(gen_addr_q[RefAddrWidth-1:0]), .rdata_o(s2_cell),
    .we_i(tbl_refs_we_i), .waddr_i(tbl_addr_i[RefAddrWidth-1:0]), .wdata_i(tbl_data_i[LocalCellWidth-1:0]),
    // The peek port is for formal proofs only (see gbt_sync_ram).
    /* verilator lint_off PINCONNECTEMPTY */
    .peek_addr_i('0), .peek_data_o()
    /* verilator lint_on PINCONNECTEMPTY */
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

  // The formal proof (below) peeks at one counter; elsewhere the peek is unused.
  logic [LocalCellWidth-1:0] f_peek_cell;
  /* verilator lint_off UNUSEDSIGNAL */
  gbt_pkg::count_t           f_peek_count;
  /* verilator lint_on UNUSEDSIGNAL */
  gbt_sync_ram #(.Depth(CellsPerLane), .WidthBits(gbt_pkg::CounterWidthBits)) u_counters (
    .clk_i, .raddr_i(cnt_raddr), .rdata_o(cnt_rdata),
    .we_i(cnt_we), .waddr_i(cnt_waddr), .wdata_i(cnt_wdata),
    .peek_addr_i(f_peek_cell), .peek_data_o(f_peek_count)
  );
  gbt_sync_ram #(.Depth(CellsPerLane), .WidthBits(gbt_pkg::SizeWidthBits), .InitFile(SizesInitFile), .SinglePort(1'b1)) u_sizes (
    .clk_i, .raddr_i(s2_cell), .rdata_o(size_rdata),
    .we_i(tbl_sizes_we_i), .waddr_i(tbl_addr_i[LocalCellWidth-1:0]), .wdata_i(tbl_data_i[gbt_pkg::SizeWidthBits-1:0]),
    // The peek port is for formal proofs only (see gbt_sync_ram).
    /* verilator lint_off PINCONNECTEMPTY */
    .peek_addr_i('0), .peek_data_o()
    /* verilator lint_on PINCONNECTEMPTY */
  );
  assign cnt_rdata_o = cnt_rdata;

  // Forwarding is decided one clock early (the refs RAM's output against the
  // cell in S3), and both candidates are incremented side by side, so S3 is a
  // 16-bit carry chain and a mux. Saturating: an increment that carries out
  // of 16 bits stays at 2^16 - 1.
  logic s3_fwd_q;
  wire [gbt_pkg::CounterWidthBits:0] inc_ram = {1'b0, cnt_rdata} + 1'b1;
  wire [gbt_pkg::CounterWidthBits:0] inc_fwd = {1'b0, s4_votes_q} + 1'b1;
  wire gbt_pkg::count_t sat_ram = inc_ram[gbt_pkg::CounterWidthBits-1:0] | {gbt_pkg::CounterWidthBits{inc_ram[gbt_pkg::CounterWidthBits]}};
  wire gbt_pkg::count_t sat_fwd = inc_fwd[gbt_pkg::CounterWidthBits-1:0] | {gbt_pkg::CounterWidthBits{inc_fwd[gbt_pkg::CounterWidthBits]}};
  assign s3_old = s3_fwd_q ? s4_votes_q : cnt_rdata;  // for the assertion below
  assign s3_new = s3_fwd_q ? sat_fwd : sat_ram;

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      s2_valid_q <= 1'b0;
      s3_valid_q <= 1'b0;
      s3_fwd_q <= 1'b0;
      s4_valid_q <= 1'b0;
      s3_cell_q <= '0;
      s4_cell_q <= '0;
      s4_votes_q <= '0;
      s4_size_q <= '0;
    end else begin
      s2_valid_q <= gen_active_q;
      s3_valid_q <= s2_valid_q;
      s3_fwd_q <= s3_valid_q && s2_cell == s3_cell_q;
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

  // --------------------------------------------- S4, S5, S6: top-2, pipelined
  // The top-2 lives in local cell indices: within a bank, c / Lanes orders
  // cells exactly as c does, and the comparisons stay narrow. Ranking x
  // against a cell c needs two 16x16 products (votes_x * size_c and
  // votes_c * size_x) and a 39-bit comparison; on an iCE40 the products and
  // the comparison each take most of a clock, so they get one stage each, and
  // every multiplier input comes straight from a register:
  //   S4 (P, products): x is multiplied against four cells: the bank's best
  //     (b) and runner-up (r) as they stand now, z, the count in S6 whose
  //     update lands at the end of this clock, and y, the count in S5 whose
  //     update lands one clock later. Products go to registers (the DSPs'
  //     output registers).
  //   S5 (C, compare): the four comparisons, each split into two 16-bit
  //     chains and the tie-break so no carry chain is longer than 16 bits,
  //     and x's cell against the four cells. z's update has landed and S5
  //     knows what it did (its action), so it keeps the two comparisons that
  //     describe the best and runner-up after z (see the action table below).
  //   S6 (A, apply): likewise for y's action, which has just landed; then the
  //     update rules for x, and x's action for the stages behind it.
  // Actions and where the best and runner-up come from afterwards:
  //   ActBestInPlace: best = the voted cell (it was the best), runner unchanged
  //   ActNewBest:     best = the voted cell, runner = the old best
  //   ActRunner:      best unchanged, runner = the voted cell
  //   ActNone:        both unchanged
  // Counts only grow within a frame, so the incremental top-2 is exact: a cell
  // that overtakes the best pushes it to runner-up; one that overtakes the
  // runner-up replaces it. Exact whatever the sequence of cells. Latency from
  // S3: 3 clocks. Eight 16x16 multipliers per lane (all eight of a UP5K).
  typedef enum logic [1:0] {ActNone, ActBestInPlace, ActNewBest, ActRunner} action_e;

  logic                      best_valid_q, runner_valid_q;
  logic [LocalCellWidth-1:0] best_cell_q, runner_cell_q;
  gbt_pkg::count_t           best_votes_q, runner_votes_q;
  gbt_pkg::size_t            best_size_q, runner_size_q;
  logic [31:0]               votes_q;

  localparam int unsigned ProductWidth = gbt_pkg::CounterWidthBits + gbt_pkg::SizeWidthBits;
  localparam int unsigned Half = ProductWidth / 2;
  typedef logic [ProductWidth-1:0] product_t;

  // S5 (C) registers: x with its products against b, r, z and y.
  logic                      c_valid_q;
  logic [LocalCellWidth-1:0] c_cell_q, c_b_cell_q, c_r_cell_q, c_z_cell_q;
  gbt_pkg::count_t           c_votes_q;
  gbt_pkg::size_t            c_size_q;
  product_t                  c_xb_q, c_bx_q, c_xr_q, c_rx_q, c_xz_q, c_zx_q, c_xy_q, c_yx_q;

  // S6 (A) registers.
  logic                      a_valid_q;
  logic [LocalCellWidth-1:0] a_cell_q;
  gbt_pkg::count_t           a_votes_q;
  gbt_pkg::size_t            a_size_q;
  logic                      a_beats_b_q, a_beats_r_q, a_beats_z_q, a_beats_y_q, a_is_b_q, a_is_r_q, a_is_y_q;
  action_e                   act_q, act_qq;  // S6's action one and two clocks ago

  // x ranks before c given the two products and the tie-break (lower local
  // index wins): {x_c, ~cell_x} > {c_x, ~cell_c} as two 16-bit halves.
  function automatic logic ranks_before_split(input product_t xc, input product_t cx,
                                              input logic [LocalCellWidth-1:0] cell_x,
                                              input logic [LocalCellWidth-1:0] cell_c);
    logic gt_hi, eq_hi, gt_lo, eq_lo;
    gt_hi = xc[ProductWidth-1:Half] > cx[ProductWidth-1:Half];
    eq_hi = xc[ProductWidth-1:Half] == cx[ProductWidth-1:Half];
    gt_lo = xc[Half-1:0] > cx[Half-1:0];
    eq_lo = xc[Half-1:0] == cx[Half-1:0];
    ranks_before_split = gt_hi || (eq_hi && (gt_lo || (eq_lo && cell_x < cell_c)));
  endfunction

  // S4 (P): products. Data registers carry no reset so they map into the
  // multipliers' output registers.
  always_ff @(posedge clk_i) begin
    c_xb_q <= ProductWidth'(s4_votes_q) * ProductWidth'(best_size_q);
    c_bx_q <= ProductWidth'(best_votes_q) * ProductWidth'(s4_size_q);
    c_xr_q <= ProductWidth'(s4_votes_q) * ProductWidth'(runner_size_q);
    c_rx_q <= ProductWidth'(runner_votes_q) * ProductWidth'(s4_size_q);
    c_xz_q <= ProductWidth'(s4_votes_q) * ProductWidth'(a_size_q);
    c_zx_q <= ProductWidth'(a_votes_q) * ProductWidth'(s4_size_q);
    c_xy_q <= ProductWidth'(s4_votes_q) * ProductWidth'(c_size_q);
    c_yx_q <= ProductWidth'(c_votes_q) * ProductWidth'(s4_size_q);
    c_cell_q <= s4_cell_q;
    c_votes_q <= s4_votes_q;
    c_size_q <= s4_size_q;
    c_b_cell_q <= best_cell_q;
    c_r_cell_q <= runner_cell_q;
    c_z_cell_q <= a_cell_q;
  end

  // S5 (C): comparisons and identities; act_q is z's action.
  // Validity is left to S6, which knows the current best and runner-up's:
  // beating an empty slot is decided there.
  wire c_beats_b = ranks_before_split(c_xb_q, c_bx_q, c_cell_q, c_b_cell_q);
  wire c_beats_r = ranks_before_split(c_xr_q, c_rx_q, c_cell_q, c_r_cell_q);
  wire c_beats_z = ranks_before_split(c_xz_q, c_zx_q, c_cell_q, c_z_cell_q);
  wire c_is_b = c_cell_q == c_b_cell_q;
  wire c_is_r = c_cell_q == c_r_cell_q;
  wire c_is_z = c_cell_q == c_z_cell_q;
  wire z_is_best = act_q == ActBestInPlace || act_q == ActNewBest;
  always_ff @(posedge clk_i) begin
    // The comparisons go to S6 as they are (they end long carry chains; S6
    // picks by z's action, act_qq there); the identities, short, are picked
    // here.
    a_beats_b_q <= c_beats_b;
    a_beats_r_q <= c_beats_r;
    a_beats_z_q <= c_beats_z;
    a_is_b_q <= z_is_best ? c_is_z : c_is_b;
    a_is_r_q <= (act_q == ActNewBest) ? c_is_b : ((act_q == ActRunner) ? c_is_z : c_is_r);
    a_beats_y_q <= ranks_before_split(c_xy_q, c_yx_q, c_cell_q, a_cell_q);  // y is in S6 now
    a_is_y_q <= c_cell_q == a_cell_q;
    a_cell_q <= c_cell_q;
    a_votes_q <= c_votes_q;
    a_size_q <= c_size_q;
  end

  // S6 (A): act_qq is z's action, act_q y's; a_is_b/a_is_r already describe
  // the best and runner-up after z, the comparisons are picked here.
  wire z_was_best     = act_qq == ActBestInPlace || act_qq == ActNewBest;
  wire beats_b1       = z_was_best ? a_beats_z_q : a_beats_b_q;
  wire beats_r1       = (act_qq == ActNewBest) ? a_beats_b_q : ((act_qq == ActRunner) ? a_beats_z_q : a_beats_r_q);
  wire y_is_best      = act_q == ActBestInPlace || act_q == ActNewBest;
  wire x_is_best      = y_is_best ? a_is_y_q : a_is_b_q;
  wire x_beats_best   = y_is_best ? a_beats_y_q : beats_b1;
  wire x_is_runner    = (act_q == ActNewBest) ? a_is_b_q : ((act_q == ActRunner) ? a_is_y_q : a_is_r_q);
  wire x_beats_runner = (act_q == ActNewBest) ? beats_b1 : ((act_q == ActRunner) ? a_beats_y_q : beats_r1);

  action_e act;
  always_comb begin
    act = ActNone;
    if (a_valid_q) begin
      if (best_valid_q && x_is_best) act = ActBestInPlace;
      else if (!best_valid_q || x_beats_best) act = ActNewBest;
      else if (!runner_valid_q || x_is_runner || x_beats_runner) act = ActRunner;
    end
  end

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      c_valid_q <= 1'b0;
      a_valid_q <= 1'b0;
    end else begin
      c_valid_q <= s4_valid_q;
      a_valid_q <= c_valid_q;
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
      act_q <= ActNone;
      act_qq <= ActNone;
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
      act_q <= ActNone;
      act_qq <= ActNone;
    end else begin
      if (s3_valid_q) votes_q <= votes_q + 1;
      unique case (act)
        ActBestInPlace: begin
          // The size too: after a clear the best holds a placeholder size.
          best_votes_q <= a_votes_q;
          best_size_q <= a_size_q;
        end
        ActNewBest: begin
          runner_valid_q <= best_valid_q;
          runner_cell_q <= best_cell_q;
          runner_votes_q <= best_votes_q;
          runner_size_q <= best_size_q;
          best_valid_q <= 1'b1;
          best_cell_q <= a_cell_q;
          best_votes_q <= a_votes_q;
          best_size_q <= a_size_q;
        end
        ActRunner: begin
          runner_valid_q <= 1'b1;
          runner_cell_q <= a_cell_q;
          runner_votes_q <= a_votes_q;
          runner_size_q <= a_size_q;
        end
        default: ;
      endcase
      act_q <= act;
      act_qq <= act_q;
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
  assign idle_o = fifo_empty && !gen_active_q && !s2_valid_q && !s3_valid_q && !s4_valid_q && !c_valid_q && !a_valid_q && !clearing_q;

  // Checked in simulation (Verilator --assert) on every clock of the co-simulation:
  // counters never wrap and never decrease within a frame — each write is the
  // value read plus one, or the saturated maximum; addresses stay in range;
  // the intake's slack rule never pushes into a full FIFO.
  // Assertions look at rst_ni only to stay quiet during reset; no logic is
  // built from that synchronous use.
`ifndef FORMAL
  assign f_peek_cell = '0;
  /* verilator lint_off SYNCASYNCNET */
  always_ff @(posedge clk_i) begin
    if (rst_ni && s3_valid_q && !clearing_q) begin
      CounterIncrements: assert (s3_new == s3_old + 1'b1 || (s3_old == '1 && s3_new == '1));
      ForwardDecidedEarly: assert (s3_fwd_q == (s4_valid_q && s4_cell_q == s3_cell_q));
      CellInRange: assert (32'(s3_cell_q) < CellsPerLane);
    end
    if (rst_ni && range_push_i) NoPushWhenFull: assert (!fifo_full);
  end
  /* verilator lint_on SYNCASYNCNET */
`else
  // Proved by hdl/formal/lane.sh with yosys-smtbmc (BMC and k-induction) on
  // a small instance. The environment is what gbt_voter guarantees: clear
  // only while idle, no push into a full FIFO or while clearing, ranges
  // non-empty and inside the refs memory, the table not written mid-frame;
  // and a valid table (references name cells of the bank). The memories'
  // own assertions (gbt_sync_ram: every read and write address in range)
  // are proved along.
  logic f_started_q = 1'b0;
  always_ff @(posedge clk_i) f_started_q <= 1'b1;
  // With the lane as the proof's top (FORMAL_LANE) these are assumptions;
  // inside gbt_voter's proof they are obligations the voter must meet.
`ifdef FORMAL_LANE
  `define GBT_LANE_ENV(expr) assume (expr)
`else
  `define GBT_LANE_ENV(expr) assert (expr)
`endif
  always_comb begin
    if (!f_started_q) assume (!rst_ni);
    if (rst_ni && clear_i) `GBT_LANE_ENV(idle_o);
    if (rst_ni && range_push_i) begin
      `GBT_LANE_ENV(!fifo_full && !clearing_q && !clear_i);
      `GBT_LANE_ENV(range_count_i != '0);
      `GBT_LANE_ENV(32'(range_begin_i) + 32'(range_count_i) <= RefsPerLane);
    end
    assume (!tbl_refs_we_i && !tbl_sizes_we_i);
    // A valid table: every word of the refs memory is a cell of this bank.
    assume (32'(s2_cell) < CellsPerLane);
    // The FIFO hands out what was pushed (hdl/formal/fifo.sh proves it), so
    // its head is a range that was assumed valid on the way in.
    if (!fifo_empty) assume (head_count != '0 && 32'(head_begin) + 32'(head_count) <= RefsPerLane);
    // The readback port's contract.
    assume (32'(cnt_raddr_i) < CellsPerLane);
  end

  // One counter, chosen by the solver (so the proof covers every counter),
  // shadowed: f_shadow_q is what its RAM word holds once written.
  (* anyconst *) logic [LocalCellWidth-1:0] f_cell;
  assign f_peek_cell = f_cell;
  logic            f_known_q;
  gbt_pkg::count_t f_shadow_q;
  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) f_known_q <= 1'b0;
    else if (cnt_we && cnt_waddr == f_cell) begin
      f_known_q <= 1'b1;
      f_shadow_q <= cnt_wdata;
    end
  end

  always_comb begin
    if (rst_ni) begin
      // Addresses in range: the refs address while generating, the counter
      // address while clearing.
      if (gen_active_q) assert (32'(gen_addr_q) < RefsPerLane);
      if (gen_active_q) assert (gen_left_q != '0 && gen_last_q == (gen_left_q == RangeCountWidth'(1)));
      if (clearing_q) assert (32'(clear_addr_q) < CellsPerLane);
      // The read-modify-write sees the counter's current value (forwarding
      // is right), so each vote writes that value plus one, or the
      // saturated maximum: a counter never decreases and never wraps
      // between clears.
      if (s3_valid_q && s3_cell_q == f_cell && f_known_q) begin
        assert (s3_old == f_shadow_q);
        assert (s3_new == ((f_shadow_q == '1) ? f_shadow_q : f_shadow_q + 1'b1));
      end
      // Helpers for the induction: the RAM word holds the shadow, S4 holds
      // what S3 wrote last clock, and the early forwarding flag agrees with
      // the cells, generator state is a valid range.
      if (f_known_q) assert (f_peek_count == f_shadow_q);
      if (gen_active_q) assert (32'(gen_addr_q) + 32'(gen_left_q) <= RefsPerLane);
      if (s4_valid_q && s4_cell_q == f_cell && f_known_q) assert (s4_votes_q == f_shadow_q);
      if (s3_valid_q) assert (s3_fwd_q == (s4_valid_q && s4_cell_q == s3_cell_q));
      if (clearing_q || s2_valid_q || s3_valid_q) assert (!(clearing_q && (s2_valid_q || s3_valid_q)));
    end
  end
`endif

endmodule

`default_nettype wire
