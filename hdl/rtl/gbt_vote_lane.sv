// gbt_vote_lane — one voting lane: the counters of one bank of cells
// (cells c with c % Lanes == LaneIndex, at local address c / Lanes).
//
// Pipeline (one vote per clock in steady state; no stall, whatever the cells):
//
//   G   range generator: pops {begin, count} ranges from the FIFO and issues
//       one reference address per clock; the next range is loaded in the
//       cycle of the last reference, so back-to-back ranges have no bubble.
//   S2  refs RAM data = local cell index, registered (S2b; the SPRAM's
//       output is slow) before it addresses the counter and size reads.
//   S3  counter data; forwarding: if the previous vote (now in S4) hit the
//       same counter, its new value replaces the RAM word (the RAM is
//       read-first, so a read in the cycle of that write returned the old
//       word; a write lands before the read one cycle later, so one-deep
//       forwarding is enough; the match is decided a clock early). new =
//       old + 1, saturating at 2^16 - 1 like the kernel; written back in
//       this cycle.
//   S4-S6 a ring of four top-2 lists (best, runner-up) travelling with the
//       votes: products, comparisons, update (see below). Counts only grow
//       within a frame, so each list is exact for the votes it saw; merge_i
//       merges the four into the outputs at frame end (30 clocks).
//
// Latency from FIFO push to top-2 update: 7 clocks for a range's first vote.
// Clearing (clear_i) sweeps the bank's counters, one per clock
// (CellsPerLane clocks), and resets the top-2 lists to the bank's two lowest
// cells with zero votes — exactly where the kernel's ranking starts.
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
  input  logic merge_i,            // merge the top-2 ring into the outputs (must be idle; 30 clocks)
  input  logic [31:0] cell_count_i, // cells of the loaded table (all banks)
  output logic idle_o,             // nothing queued, in flight, clearing or merging (registered)
  output logic merging_o,          // merge_i's 30 clocks

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
  logic [LocalCellWidth-1:0] s2_cell, s2b_cell_q;
  logic s2_valid_q, s2b_valid_q;
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
  /* verilator lint_off UNUSEDSIGNAL */
  logic                      s4_injected_q;  // S4 holds a merge entry (read by the formal proof only)
  /* verilator lint_on UNUSEDSIGNAL */
  logic [LocalCellWidth-1:0] s3_cell_q, s4_cell_q;
  gbt_pkg::count_t                    s4_votes_q;
  gbt_pkg::size_t                     s4_size_q;
  gbt_pkg::count_t                    cnt_rdata, s3_old, s3_new;
  gbt_pkg::size_t                     size_rdata;

  logic                      clearing_q, clearing_d;
  logic [LocalCellWidth-1:0] clear_addr_q;

  logic                      cnt_we;
  logic [LocalCellWidth-1:0] cnt_waddr, cnt_raddr;
  gbt_pkg::count_t                    cnt_wdata;

  assign cnt_raddr = s2b_valid_q ? s2b_cell_q : cnt_raddr_i;
  assign cnt_we    = clearing_q || s3_valid_q;
  assign cnt_waddr = clearing_q ? clear_addr_q : s3_cell_q;
  // While clearing, s3_new is the zero held in s4_plus1_q (no mux on the
  // write data: S3 is the lane's longest path).
  assign cnt_wdata = s3_new;

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
    .clk_i, .raddr_i(s2b_cell_q), .rdata_o(size_rdata),
    .we_i(tbl_sizes_we_i), .waddr_i(tbl_addr_i[LocalCellWidth-1:0]), .wdata_i(tbl_data_i[gbt_pkg::SizeWidthBits-1:0]),
    // The peek port is for formal proofs only (see gbt_sync_ram).
    /* verilator lint_off PINCONNECTEMPTY */
    .peek_addr_i('0), .peek_data_o()
    /* verilator lint_on PINCONNECTEMPTY */
  );
  assign cnt_rdata_o = cnt_rdata;

  // Forwarding is decided one clock early (the cell read against the cell in
  // S3), and S4 also keeps its count plus one (s4_plus1_q), so a forwarded
  // vote's count is a register and S3's longest path is one 16-bit carry
  // chain from the RAM, then a mux. Saturating: an increment that carries out
  // of 16 bits stays at 2^16 - 1 (and saturating twice is saturating +2).
  localparam int unsigned CW = gbt_pkg::CounterWidthBits;
  logic s3_fwd_q;
  gbt_pkg::count_t s4_plus1_q;
  wire [CW:0] inc1_ram = {1'b0, cnt_rdata} + (CW + 1)'(1);
  wire [CW:0] inc2_ram = {1'b0, cnt_rdata} + (CW + 1)'(2);
  wire [CW:0] inc1_fwd = {1'b0, s4_plus1_q} + (CW + 1)'(1);
  wire gbt_pkg::count_t sat1_ram = inc1_ram[CW-1:0] | {CW{inc1_ram[CW]}};
  wire gbt_pkg::count_t sat2_ram = inc2_ram[CW-1:0] | {CW{inc2_ram[CW]}};
  wire gbt_pkg::count_t sat1_fwd = inc1_fwd[CW-1:0] | {CW{inc1_fwd[CW]}};
  assign s3_old = s3_fwd_q ? s4_votes_q : cnt_rdata;  // for the assertions below
  logic s3_take_plus1_q;  // s3_fwd_q, or clearing (then s4_plus1_q is zero)
  assign s3_new = s3_take_plus1_q ? s4_plus1_q : sat1_ram;
  wire gbt_pkg::count_t s3_plus1 = s3_fwd_q ? sat1_fwd : sat2_ram;

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      s2_valid_q <= 1'b0;
      s2b_valid_q <= 1'b0;
      s2b_cell_q <= '0;
      s3_valid_q <= 1'b0;
      s3_fwd_q <= 1'b0;
      s3_take_plus1_q <= 1'b0;
      s4_valid_q <= 1'b0;
      s4_injected_q <= 1'b0;
      s3_cell_q <= '0;
      s4_cell_q <= '0;
      s4_votes_q <= '0;
      s4_plus1_q <= '0;
      s4_size_q <= '0;
    end else begin
      s2_valid_q <= gen_active_q;
      s2b_valid_q <= s2_valid_q;
      s2b_cell_q <= s2_cell;
      s3_valid_q <= s2b_valid_q;
      s3_fwd_q <= s3_valid_q && s2b_cell_q == s3_cell_q;
      s3_take_plus1_q <= (s3_valid_q && s2b_cell_q == s3_cell_q) || clearing_d;
      s3_cell_q <= s2b_cell_q;
      // While merging (the pipeline is otherwise empty) S4 takes the
      // merge's entries instead of S3's votes.
      s4_valid_q <= merge_inject ? inject_entry.valid : s3_valid_q;
      s4_injected_q <= merge_inject;
      s4_cell_q <= merge_inject ? inject_entry.local_cell : s3_cell_q;
      s4_votes_q <= merge_inject ? inject_entry.votes : s3_new;
      s4_plus1_q <= (clear_i || clearing_q) ? '0 : s3_plus1;  // a synchronous reset, no LUT
      s4_size_q <= merge_inject ? inject_entry.size : size_rdata;
    end
  end

  assign clearing_d = clear_i || (clearing_q && 32'(clear_addr_q) != CellsPerLane - 1);
  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      clearing_q <= 1'b0;
      clear_addr_q <= '0;
    end else if (clear_i) begin
      clearing_q <= clearing_d;
      clear_addr_q <= '0;
    end else if (clearing_q) begin
      clearing_q <= clearing_d;
      clear_addr_q <= clear_addr_q + 1'b1;
    end
  end

  // ------------------------------------------------- S4, S5, S6: top-2 ring
  // The top-2 lives in local cell indices: within a bank, c / Lanes orders
  // cells exactly as c does, and the comparisons stay narrow.
  //
  // Ranking a count x against a cell c needs two 16x16 products and a 39-bit
  // comparison; on an iCE40 the products, the way from the DSPs to the
  // fabric, the comparison and the update each take most of a clock. So four
  // top-2 lists (slots) travel round a ring, one stage a clock, alongside the
  // votes: the vote in S4 (P) is multiplied against the slot in ring_p, its
  // products move into the fabric in S4b (Q), are compared in S5 (C) and
  // update the slot in S6 (A), which writes it back into ring_p. Each slot
  // comes back to S4 four clocks later with every update applied, so there
  // are no hazards and no forwarding; four multipliers per lane. Votes go to
  // the slots round-robin; a bubble passes its slot on unchanged.
  //
  // Each slot holds the top-2 of the counts it has seen, a cell's latest count
  // counting (counts only grow within a frame). The true best and runner-up,
  // at their final counts, are each in the top-2 of the slot that saw their
  // last vote (only the true best can outrank the runner-up, in any slot), so
  // merging the slots gives the bank's exact top-2. Merging (merge_i, while
  // idle) feeds three slots' six entries through the same pipeline into the
  // fourth, four clocks apart; an entry naming a cell the slot already holds
  // replaces it only if it ranks higher, so stale counts change nothing.
  // Then the result is copied to the outputs: 30 clocks.
  localparam int unsigned ProductWidth = gbt_pkg::CounterWidthBits + gbt_pkg::SizeWidthBits;
  localparam int unsigned Half = ProductWidth / 2;
  typedef logic [ProductWidth-1:0] product_t;

  // Field types written out: yosys 0.23 resolves no package types inside a
  // struct, and reads no named assignment patterns (hence the concatenations).
  typedef struct packed {
    logic                                best_valid;
    logic [LocalCellWidth-1:0]           best_cell;
    logic [gbt_pkg::CounterWidthBits-1:0] best_votes;
    logic [gbt_pkg::SizeWidthBits-1:0]    best_size;
    logic                                runner_valid;
    logic [LocalCellWidth-1:0]           runner_cell;
    logic [gbt_pkg::CounterWidthBits-1:0] runner_votes;
    logic [gbt_pkg::SizeWidthBits-1:0]    runner_size;
  } top2_t;

  typedef struct packed {
    logic                                valid;
    logic [LocalCellWidth-1:0]           local_cell;
    logic [gbt_pkg::CounterWidthBits-1:0] votes;
    logic [gbt_pkg::SizeWidthBits-1:0]    size;
  } entry_t;

  localparam int unsigned EntryBits = 1 + LocalCellWidth + gbt_pkg::CounterWidthBits + gbt_pkg::SizeWidthBits;

  // Zero votes everywhere: the kernel's order is then the cell index.
  top2_t top2_cleared;
  assign top2_cleared = {LaneIndex < cell_count_i, LocalCellWidth'(0), gbt_pkg::CounterWidthBits'(0), gbt_pkg::SizeWidthBits'(1),
                         LaneIndex + Lanes < cell_count_i, LocalCellWidth'(1), gbt_pkg::CounterWidthBits'(0),
                         gbt_pkg::SizeWidthBits'(1)};

  top2_t ring_p_q, ring_q_q, ring_c_q, ring_a_q, ring_p_d, out_q;
  logic [31:0] votes_q;

  // x ranks before c given the two products and the tie-break (x's local
  // index below c's, compared in S4): {x_c, lt} > {c_x, 0} from two 16-bit
  // carry chains and two equality trees side by side.
  function automatic logic ranks_before_split(input product_t xc, input product_t cx, input logic lt);
    logic gt_hi, eq_hi, gt_lo, eq_lo;
    gt_hi = xc[ProductWidth-1:Half] > cx[ProductWidth-1:Half];
    eq_hi = xc[ProductWidth-1:Half] == cx[ProductWidth-1:Half];
    gt_lo = xc[Half-1:0] > cx[Half-1:0];
    eq_lo = xc[Half-1:0] == cx[Half-1:0];
    ranks_before_split = gt_hi || (eq_hi && (gt_lo || (eq_lo && lt)));
  endfunction

  // S4 (P): products against ring_p's best and runner-up. Data registers
  // carry no reset so they map into the multipliers' output registers.
  logic                      q_valid_q, c_valid_q;
  logic [LocalCellWidth-1:0] q_cell_q, c_cell_q;
  gbt_pkg::count_t           q_votes_q, c_votes_q;
  gbt_pkg::size_t            q_size_q, c_size_q;
  product_t                  q_xb_q, q_bx_q, q_xr_q, q_rx_q;
  product_t                  c_xb_q, c_bx_q, c_xr_q, c_rx_q;
  logic                      q_lt_b_q, q_lt_r_q, c_lt_b_q, c_lt_r_q;  // x's cell below the best's, the runner-up's
  always_ff @(posedge clk_i) begin
    q_xb_q <= ProductWidth'(s4_votes_q) * ProductWidth'(ring_p_q.best_size);
    q_bx_q <= ProductWidth'(ring_p_q.best_votes) * ProductWidth'(s4_size_q);
    q_xr_q <= ProductWidth'(s4_votes_q) * ProductWidth'(ring_p_q.runner_size);
    q_rx_q <= ProductWidth'(ring_p_q.runner_votes) * ProductWidth'(s4_size_q);
    q_cell_q <= s4_cell_q;
    q_lt_b_q <= s4_cell_q < ring_p_q.best_cell;
    q_lt_r_q <= s4_cell_q < ring_p_q.runner_cell;
    q_votes_q <= s4_votes_q;
    q_size_q <= s4_size_q;
  end

  // S4b (Q): the products copied from the DSPs' output registers into the
  // fabric, next to the comparators (the DSPs sit at the die's edge). An
  // asynchronous reset keeps these in the fabric (yosys 0.23's ice40_dsp pass
  // crashes trying to pack a second register stage into the DSPs).
  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      c_xb_q <= '0;
      c_bx_q <= '0;
      c_xr_q <= '0;
      c_rx_q <= '0;
    end else begin
      c_xb_q <= q_xb_q;
      c_bx_q <= q_bx_q;
      c_xr_q <= q_xr_q;
      c_rx_q <= q_rx_q;
    end
  end
  always_ff @(posedge clk_i) begin
    c_cell_q <= q_cell_q;
    c_lt_b_q <= q_lt_b_q;
    c_lt_r_q <= q_lt_r_q;
    c_votes_q <= q_votes_q;
    c_size_q <= q_size_q;
  end

  // S5 (C): comparisons and identities against the same slot, now ring_c.
  logic                      a_valid_q;
  logic [LocalCellWidth-1:0] a_cell_q;
  gbt_pkg::count_t           a_votes_q;
  gbt_pkg::size_t            a_size_q;
  logic                      a_beats_b_q, a_beats_r_q, a_is_b_q;
  always_ff @(posedge clk_i) begin
    a_beats_b_q <= !ring_c_q.best_valid || ranks_before_split(c_xb_q, c_bx_q, c_lt_b_q);
    a_beats_r_q <= !ring_c_q.runner_valid || ranks_before_split(c_xr_q, c_rx_q, c_lt_r_q);
    a_is_b_q <= ring_c_q.best_valid && c_cell_q == ring_c_q.best_cell;
    a_cell_q <= c_cell_q;
    a_votes_q <= c_votes_q;
    a_size_q <= c_size_q;
  end

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      q_valid_q <= 1'b0;
      c_valid_q <= 1'b0;
      a_valid_q <= 1'b0;
    end else begin
      q_valid_q <= s4_valid_q;
      c_valid_q <= q_valid_q;
      a_valid_q <= c_valid_q;
    end
  end

  // S6 (A): the update of the slot in ring_a, into ring_p.
  //   best in place:  x is the best's cell and ranks higher (a newer count)
  //   new best:       x ranks before the best; the best becomes the runner-up
  //   runner-up:      x ranks before the runner-up (in place if its cell;
  //                   no identity test needed: a cell cannot outrank itself
  //                   without ranking higher)
  // An entry of a cell already held that does not rank higher changes nothing.
  always_comb begin
    ring_p_d = ring_a_q;
    if (a_valid_q) begin
      if (a_is_b_q) begin
        if (a_beats_b_q) begin
          ring_p_d.best_votes = a_votes_q;
          ring_p_d.best_size = a_size_q;  // after a clear the best holds a placeholder size
        end
      end else if (a_beats_b_q) begin
        ring_p_d.runner_valid = ring_a_q.best_valid;
        ring_p_d.runner_cell = ring_a_q.best_cell;
        ring_p_d.runner_votes = ring_a_q.best_votes;
        ring_p_d.runner_size = ring_a_q.best_size;
        ring_p_d.best_valid = 1'b1;
        ring_p_d.best_cell = a_cell_q;
        ring_p_d.best_votes = a_votes_q;
        ring_p_d.best_size = a_size_q;
      end else if (a_beats_r_q) begin
        ring_p_d.runner_valid = 1'b1;
        ring_p_d.runner_cell = a_cell_q;
        ring_p_d.runner_votes = a_votes_q;
        ring_p_d.runner_size = a_size_q;
      end
    end
  end

  // Merge: snapshot ring_p, ring_q and ring_c (merge_q = 1), feed their six
  // entries into S4 at merge_q = 4, 8, ..., 24 (each meets the slot that was
  // in ring_a, now in ring_p, four clocks apart), copy ring_p to the outputs
  // at 29.
  logic [4:0] merge_q;
  entry_t     merge_entry_q [6];
  wire        merge_inject = merge_q != '0 && merge_q[1:0] == 2'd0 && merge_q <= 5'd24;
  entry_t     inject_entry;
  always_comb begin
    unique case (merge_q)
      5'd8: inject_entry = merge_entry_q[1];
      5'd12: inject_entry = merge_entry_q[2];
      5'd16: inject_entry = merge_entry_q[3];
      5'd20: inject_entry = merge_entry_q[4];
      5'd24: inject_entry = merge_entry_q[5];
      default: inject_entry = merge_entry_q[0];
    endcase
  end

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      ring_p_q <= '0;
      ring_q_q <= '0;
      ring_c_q <= '0;
      ring_a_q <= '0;
      out_q <= '0;
      votes_q <= '0;
      merge_q <= '0;
    end else if (clear_i) begin
      ring_p_q <= top2_cleared;
      ring_q_q <= top2_cleared;
      ring_c_q <= top2_cleared;
      ring_a_q <= top2_cleared;
      out_q <= top2_cleared;
      votes_q <= '0;
      merge_q <= '0;
    end else begin
      if (s3_valid_q) votes_q <= votes_q + 1;
      ring_p_q <= ring_p_d;
      ring_q_q <= ring_p_q;
      ring_c_q <= ring_q_q;
      ring_a_q <= ring_c_q;
      if (merge_i) merge_q <= 5'd1;
      else if (merge_q != '0) merge_q <= (merge_q == 5'd29) ? '0 : merge_q + 1'b1;
      if (merge_q == 5'd29) out_q <= ring_p_q;
    end
  end

  always_ff @(posedge clk_i) begin
    if (merge_i) begin
      // A top-2 is {best entry, runner-up entry} in entry_t's layout.
      merge_entry_q[0] <= ring_p_q[2*EntryBits-1 -: EntryBits];
      merge_entry_q[1] <= ring_p_q[EntryBits-1:0];
      merge_entry_q[2] <= ring_q_q[2*EntryBits-1 -: EntryBits];
      merge_entry_q[3] <= ring_q_q[EntryBits-1:0];
      merge_entry_q[4] <= ring_c_q[2*EntryBits-1 -: EntryBits];
      merge_entry_q[5] <= ring_c_q[EntryBits-1:0];
    end
  end

  assign best_valid_o = out_q.best_valid;
  assign best_cell_o = 32'(out_q.best_cell) * Lanes + LaneIndex;
  assign best_votes_o = out_q.best_votes;
  assign best_size_o = out_q.best_size;
  assign runner_valid_o = out_q.runner_valid;
  assign runner_cell_o = 32'(out_q.runner_cell) * Lanes + LaneIndex;
  assign runner_votes_o = out_q.runner_votes;
  assign runner_size_o = out_q.runner_size;
  assign votes_o = votes_q;
  // Idle, registered (the voter's state machine waits on it): nothing
  // queued, in flight, clearing or merging, and nothing started this clock
  // (so a registered idle is never stale).
  wire idle_now = fifo_empty && !gen_active_q && !s2_valid_q && !s2b_valid_q && !s3_valid_q && !s4_valid_q && !q_valid_q && !c_valid_q
                  && !a_valid_q && !clearing_q && merge_q == '0;
  logic idle_q;
  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) idle_q <= 1'b1;  // out of reset, nothing is queued
    else idle_q <= idle_now && !range_push_i && !clear_i && !merge_i;
  end
  assign idle_o = idle_q;
  assign merging_o = merge_q != '0;

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
      ForwardDecidedEarly: assert (s3_fwd_q == (s4_valid_q && s4_cell_q == s3_cell_q) && s3_take_plus1_q == s3_fwd_q);
      CellInRange: assert (32'(s3_cell_q) < CellsPerLane);
    end
    if (rst_ni && range_push_i) NoPushWhenFull: assert (!fifo_full);
    if (rst_ni && clearing_q) ClearWritesZero: assert (cnt_wdata == '0);
  end
  /* verilator lint_on SYNCASYNCNET */
`else
  // Proved by hdl/formal/prove.sh lane with yosys-smtbmc (BMC and k-induction) on
  // a small instance. The environment is what gbt_voter guarantees: clear
  // and merge only while idle, no push into a full FIFO or while clearing or
  // merging, ranges
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
    if (rst_ni && clear_i) `GBT_LANE_ENV(idle_o && !merge_i);
    if (rst_ni && merge_i) `GBT_LANE_ENV(idle_o);
    if (rst_ni && range_push_i) begin
      `GBT_LANE_ENV(!fifo_full && !clearing_q && !clear_i && merge_q == '0 && !merge_i);
      `GBT_LANE_ENV(range_count_i != '0);
      `GBT_LANE_ENV(32'(range_begin_i) + 32'(range_count_i) <= RefsPerLane);
    end
    assume (!tbl_refs_we_i && !tbl_sizes_we_i);
    // A valid table: every word of the refs memory is a cell of this bank.
    assume (32'(s2_cell) < CellsPerLane);
    // The FIFO hands out what was pushed (hdl/formal/prove.sh fifo proves it), so
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
      if (s4_valid_q && !s4_injected_q && s4_cell_q == f_cell && f_known_q) assert (s4_votes_q == f_shadow_q);
      if (s4_valid_q && !s4_injected_q) assert (s4_plus1_q == ((s4_votes_q == '1) ? s4_votes_q : s4_votes_q + 1'b1));
      if (s3_valid_q) assert (s3_fwd_q == (s4_valid_q && s4_cell_q == s3_cell_q));
      assert (s3_take_plus1_q == (s3_fwd_q || clearing_q));
      if (clearing_q) assert (s3_take_plus1_q && s4_plus1_q == '0);
      if (clearing_q) assert (!s2_valid_q && !s2b_valid_q && !s3_valid_q);
      if (idle_q) assert (idle_now);
      if (merge_q != '0) assert (fifo_empty && !gen_active_q && !s2_valid_q && !s2b_valid_q && !s3_valid_q && !clearing_q);
      if (merge_q != '0 && s4_valid_q) assert (s4_injected_q);
    end
  end
`endif

endmodule

`default_nettype wire
