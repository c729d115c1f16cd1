// gbt_voter — the gabarit hardware voter: a stream of feature pixels in, the
// kernel's counters, best cell and runner-up out, bit for bit
// (kernel/src/voter.cpp is the golden model; tests/hdl co-simulates both).
//
// Data layout (memory images from `gabarit tables export-hdl`):
//   offsets  roi_width*roi_height words; word p holds, for each lane k at bits
//            [k*RangeWidth +: RangeWidth], {begin, count} of pixel p's
//            references that fall in lane k's bank (cells c % Lanes == k)
//   refs_k   lane k's references, as local cell indices c / Lanes
//   sizes_k  stencil sizes of lane k's cells, clamped to >= 1
//
// Handshake and timing:
//   frame_start_i (pulse, while idle or done): counters cleared in
//     CellsPerLane clocks (busy_o high, feat_ready_o low), then the frame runs.
//   feat_valid_i/feat_ready_o/feat_col_i/feat_row_i: one feature per clock at
//     most; a feature is taken when valid && ready. Features outside the ROI
//     are dropped and raise roi_error_o; features beyond MaxFeaturesPerFrame
//     are dropped and raise overflow_o (the handshake never stalls on them).
//   intake: clock t takes a feature, t+1 compares it with the ROI and forms
//     its pixel index, t+2 accepts or rejects it, t+3 reads its offsets
//     word, t+4 registers it, t+5 registers each lane's range and whether
//     it is non-empty, t+6 pushes it into that lane's FIFO. Ready needs
//     seven free FIFO slots in every lane (six in flight), seen one clock
//     earlier (ready is registered).
//   frame_end_i (pulse, any time after frame_start_i, even while clearing —
//     it is latched): the pipelines drain, each lane merges its top-2 ring
//     (31 clocks), the lanes' top-2 lists merge (at most 4*Lanes clocks; none
//     with one lane), then result_valid_o stays high with
//     best/runner/votes/features/cycles until the next frame_start_i.
//   Steady state: each lane retires one vote per clock; with the references
//     of a pixel spread over the banks, Lanes votes per clock.
`default_nettype none

module gbt_voter #(
  parameter int unsigned Lanes = 1,                 // 1, 2, 4 or 8
  parameter int unsigned CellCapacity = 128,        // memories are sized for these capacities;
  parameter int unsigned PixelCapacity = 4096,      // the table in use is described by the
  parameter int unsigned RefsPerLane = 32768,       // cell_count_i / roi_*_i inputs
  parameter int unsigned MaxFeaturesPerFrame = 65535,
  parameter int unsigned FifoDepth = 16,
  parameter int unsigned MaxRangeCount = 0,         // references of one pixel in one lane; 0 = CellsPerLane
  parameter InitPrefix = "",                        // "<dir>/": offsets.mem, refs_<k>.mem, sizes_<k>.mem
  localparam int unsigned CellsPerLane = (CellCapacity + Lanes - 1) / Lanes,
  localparam int unsigned PixelWidth = (PixelCapacity > 1) ? $clog2(PixelCapacity) : 1,
  localparam int unsigned OffsetWidth = $clog2(RefsPerLane + 1),
  localparam int unsigned RangeCountWidth = $clog2(((MaxRangeCount == 0) ? CellsPerLane : MaxRangeCount) + 1),
  localparam int unsigned RangeWidth = OffsetWidth + RangeCountWidth,
  localparam int unsigned LocalCellWidth = (CellsPerLane > 1) ? $clog2(CellsPerLane) : 1,
  localparam int unsigned LaneWidth = (Lanes > 1) ? $clog2(Lanes) : 1,
  localparam int unsigned LaneShift = $clog2(Lanes),  // Lanes is a power of two: c / Lanes = c >> LaneShift
  localparam int unsigned TableDataWidth = (Lanes * RangeWidth > 32) ? Lanes * RangeWidth : 32
) (
  input  logic clk_i,
  input  logic rst_ni,

  // The loaded table (constants in an FPGA build; registers in a SoC).
  input  logic [31:0] cell_count_i,   // 1 .. CellCapacity
  input  logic [15:0] roi_width_i,    // roi_width_i * roi_height_i <= PixelCapacity
  input  logic [15:0] roi_height_i,

  input  logic frame_start_i,
  input  logic frame_end_i,
  output logic busy_o,

  input  logic        feat_valid_i,
  output logic        feat_ready_o,
  input  logic [15:0] feat_col_i,
  input  logic [15:0] feat_row_i,

  output logic        result_valid_o,
  output logic [31:0] best_cell_o,
  output gbt_pkg::count_t      best_votes_o,
  output logic        runner_valid_o,
  output logic [31:0] runner_cell_o,
  output gbt_pkg::count_t      runner_votes_o,
  output logic [31:0] votes_o,
  output logic [31:0] features_o,
  output logic [31:0] cycles_o,       // frame_start_i to result_valid_o
  output logic        overflow_o,
  output logic        roi_error_o,

  // Table loading while idle: sel 0 = offsets word, 1 = lane refs, 2 = lane sizes.
  input  logic                      tbl_we_i,
  input  logic [1:0]                tbl_sel_i,
  input  logic [LaneWidth-1:0]      tbl_lane_i,
  input  logic [31:0]               tbl_addr_i,
  input  logic [TableDataWidth-1:0] tbl_data_i,

  // Counter readback while idle or done: value of cell cnt_cell_i one clock later.
  input  logic [31:0] cnt_cell_i,
  output gbt_pkg::count_t      cnt_data_o
);

  // Package items are named in full: yosys 0.23 reads no `import` in a module.

`ifndef SYNTHESIS
  initial begin
    if (!(Lanes == 1 || Lanes == 2 || Lanes == 4 || Lanes == 8)) $fatal(1, "Lanes must be 1, 2, 4 or 8");
    if (CellCapacity < 1 || PixelCapacity < 1) $fatal(1, "capacities must be at least 1");
  end
`endif

  typedef enum logic [2:0] {StIdle, StClear, StRun, StDrain, StLaneMerge, StMerge, StDone} state_e;
  state_e state_q, state_d;
  logic end_pending_q;  // frame_end_i seen during StClear or StRun

  // ----------------------------------------------------------------- intake
  logic [Lanes-1:0] lane_idle, lane_room, lane_pushing;
  /* verilator lint_off UNUSEDSIGNAL */
  logic [Lanes-1:0] lane_merging;  // read by the formal proof only
  /* verilator lint_on UNUSEDSIGNAL */
  logic [$clog2(FifoDepth):0] lane_free [Lanes];
  for (genvar k = 0; k < Lanes; k++) begin : g_room
    assign lane_room[k] = lane_free[k] >= 8;
  end
  // Room is registered so that ready is one LUT from flip-flops (the FIFO's
  // free count is a subtraction and a comparison; the source's valid and our
  // ready meet in the source's enable). A lane's free count drops by at most
  // one per clock, so eight free slots one clock ago still mean seven now.
  logic room_all_q;
  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) room_all_q <= 1'b0;
    else room_all_q <= &lane_room;
  end

  // Intake stages keep the input pins, the ROI comparisons with the
  // pixel-index multiply-add, the accept decision and the RAM address apart,
  // one clock each (each was the critical path of the iCE40 build in turn):
  //   I0 (clock t):   a feature is taken and registered
  //   I1 (clock t+1): ROI comparisons registered; pixel index, first half
  //   I2 (clock t+2): capacity check, accept or reject; pixel index registered
  //   I3 (clock t+3): offsets RAM read
  //   I4 (clock t+4): offsets word registered (block RAM clock-to-out is slow)
  //   I5 (clock t+5): each lane's range and push decision (non-empty) registered
  //   I6 (clock t+6): the range pushed into its lane's FIFO
  // Six features can be in flight, so ready needs seven free slots per lane.
  assign feat_ready_o = (state_q == StRun) && room_all_q;
  wire take = feat_valid_i && feat_ready_o;

  logic        in_valid_q, chk_valid_q, chk_in_roi_q;
  logic [15:0] in_col_q, in_row_q;
  logic [31:0] features_q;
  logic        overflow_q, roi_error_q, pixel_valid_q, pushing_q;
  logic [PixelWidth-1:0] pixel_q;
  // Capacity as a registered flag, kept exact by a count of remaining room,
  // so accept is one LUT deep after the ROI comparison.
  localparam int unsigned RoomWidth = $clog2(MaxFeaturesPerFrame + 1);
  logic [RoomWidth-1:0] room_left_q;
  logic                 room_q;
  wire in_roi = (in_col_q < roi_width_i) && (in_row_q < roi_height_i);
  wire accept = chk_valid_q && chk_in_roi_q && room_q;
  // PixelWidth-bit arithmetic is exact whenever in_roi: row * width + col <
  // width * height <= PixelCapacity <= 2^PixelWidth.
  // Two clocks (I1, I2) in fabric adders: the DSPs all go to the lane.
  gbt_mul_add #(.WidthBits(PixelWidth)) u_pixel_index (
    .clk_i, .a_i(PixelWidth'(in_row_q)), .b_i(PixelWidth'(roi_width_i)), .c_i(PixelWidth'(in_col_q)), .y_o(pixel_q)
  );

  logic [Lanes*RangeWidth-1:0] offsets_word, offsets_word_q;
  logic                        word_valid_q;
  gbt_sync_ram #(.Depth(PixelCapacity), .WidthBits(Lanes * RangeWidth), .SinglePort(1'b1),
                 .InitFile(InitPrefix == "" ? "" : {InitPrefix, "offsets.mem"})) u_offsets (
    .clk_i, .raddr_i(pixel_q), .rdata_o(offsets_word),
    .we_i(tbl_we_i && tbl_sel_i == 2'd0), .waddr_i(tbl_addr_i[PixelWidth-1:0]),
    .wdata_i(tbl_data_i[Lanes*RangeWidth-1:0]),
    // The peek port is for formal proofs only (see gbt_sync_ram).
    /* verilator lint_off PINCONNECTEMPTY */
    .peek_addr_i('0), .peek_data_o()
    /* verilator lint_on PINCONNECTEMPTY */
  );

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      in_valid_q <= 1'b0;
      chk_valid_q <= 1'b0;
      chk_in_roi_q <= 1'b0;
      in_col_q <= '0;
      in_row_q <= '0;
      features_q <= '0;
      overflow_q <= 1'b0;
      roi_error_q <= 1'b0;
      pixel_valid_q <= 1'b0;
      word_valid_q <= 1'b0;
      offsets_word_q <= '0;
      pushing_q <= 1'b0;
      room_left_q <= RoomWidth'(MaxFeaturesPerFrame);
      room_q <= MaxFeaturesPerFrame > 0;
    end else if (frame_start_i && (state_q == StIdle || state_q == StDone)) begin
      in_valid_q <= 1'b0;
      chk_valid_q <= 1'b0;
      features_q <= '0;
      overflow_q <= 1'b0;
      roi_error_q <= 1'b0;
      pixel_valid_q <= 1'b0;
      word_valid_q <= 1'b0;
      pushing_q <= 1'b0;
      room_left_q <= RoomWidth'(MaxFeaturesPerFrame);
      room_q <= MaxFeaturesPerFrame > 0;
    end else begin
      in_valid_q <= take;
      if (take) begin
        in_col_q <= feat_col_i;
        in_row_q <= feat_row_i;
      end
      chk_valid_q <= in_valid_q;
      chk_in_roi_q <= in_roi;
      pixel_valid_q <= accept;
      word_valid_q <= pixel_valid_q;
      offsets_word_q <= offsets_word;
      pushing_q <= word_valid_q;
      if (accept) begin
        room_left_q <= room_left_q - 1'b1;
        room_q <= room_left_q != RoomWidth'(1);
      end
      // Counted one clock after acceptance (from a register, off the accept path).
      features_q <= features_q + 32'(pixel_valid_q);
      if (chk_valid_q && !chk_in_roi_q) roi_error_q <= 1'b1;
      if (chk_valid_q && chk_in_roi_q && !accept) overflow_q <= 1'b1;
    end
  end

  // ------------------------------------------------------------------ lanes
  logic        l_best_valid [Lanes], l_runner_valid [Lanes];
  logic [31:0] l_best_cell [Lanes], l_runner_cell [Lanes], l_votes [Lanes];
  gbt_pkg::count_t      l_best_votes [Lanes], l_runner_votes [Lanes], l_cnt [Lanes];
  gbt_pkg::size_t       l_best_size [Lanes], l_runner_size [Lanes];

  wire clear = frame_start_i && (state_q == StIdle || state_q == StDone);
  // Each lane merges its top-2 ring once the frame has drained (30 clocks).
  logic lane_merge, lane_merge_sent_q;
  assign lane_merge = state_q == StLaneMerge && !lane_merge_sent_q;

  for (genvar k = 0; k < Lanes; k++) begin : g_lane
    wire [RangeWidth-1:0] range = offsets_word_q[k*RangeWidth +: RangeWidth];
    // I5: the push decision registered, so the FIFO's write enables come
    // straight from flip-flops.
    logic                  push_q;
    logic [RangeWidth-1:0] range_q;
    always_ff @(posedge clk_i or negedge rst_ni) begin
      if (!rst_ni) begin
        push_q <= 1'b0;
        range_q <= '0;
      end else begin
        push_q <= pushing_q && range[RangeCountWidth-1:0] != '0;
        range_q <= range;
      end
    end
    assign lane_pushing[k] = push_q;
    gbt_vote_lane #(
      .Lanes(Lanes), .LaneIndex(k), .CellsPerLane(CellsPerLane), .RefsPerLane(RefsPerLane), .FifoDepth(FifoDepth),
      .MaxRangeCount(MaxRangeCount),
      .RefsInitFile(InitPrefix == "" ? "" : {InitPrefix, "refs_", 8'(48 + k), ".mem"}),
      .SizesInitFile(InitPrefix == "" ? "" : {InitPrefix, "sizes_", 8'(48 + k), ".mem"})
    ) u_lane (
      .clk_i, .rst_ni,
      .clear_i(clear), .merge_i(lane_merge), .cell_count_i, .idle_o(lane_idle[k]), .merging_o(lane_merging[k]),
      .range_push_i(push_q),
      .range_begin_i(range_q[RangeWidth-1:RangeCountWidth]),
      .range_count_i(range_q[RangeCountWidth-1:0]),
      .range_free_o(lane_free[k]),
      .best_valid_o(l_best_valid[k]), .best_cell_o(l_best_cell[k]), .best_votes_o(l_best_votes[k]),
      .best_size_o(l_best_size[k]),
      .runner_valid_o(l_runner_valid[k]), .runner_cell_o(l_runner_cell[k]), .runner_votes_o(l_runner_votes[k]),
      .runner_size_o(l_runner_size[k]),
      .votes_o(l_votes[k]),
      .tbl_refs_we_i(tbl_we_i && tbl_sel_i == 2'd1 && 32'(tbl_lane_i) == k),
      .tbl_sizes_we_i(tbl_we_i && tbl_sel_i == 2'd2 && 32'(tbl_lane_i) == k),
      .tbl_addr_i, .tbl_data_i(tbl_data_i[31:0]),
      .cnt_raddr_i(LocalCellWidth'(cnt_cell_i >> LaneShift)),
      .cnt_rdata_o(l_cnt[k])
    );
  end

  // Readback mux: the lane of the cell asked for one clock ago.
  logic [LaneWidth-1:0] cnt_lane_q;
  always_ff @(posedge clk_i) cnt_lane_q <= (Lanes > 1) ? LaneWidth'(cnt_cell_i) : '0;
  assign cnt_data_o = l_cnt[cnt_lane_q];

  // ------------------------------------------------------- control, merge
  // With several lanes, the lanes' top-2 lists (2*Lanes candidates) are
  // merged at frame end with one shared comparator: each candidate is first
  // compared with the merged best and, if it does not beat it, with the
  // merged runner-up in the next clock (at most 4*Lanes clocks). One lane's
  // top-2 is already the answer.
  logic [31:0] cycles_q;
  localparam int unsigned MergeWidth = $clog2(2 * Lanes + 1);
  logic [MergeWidth-1:0] merge_q;      // candidate index
  logic                  merge_runner_q;  // second phase: compare with the runner-up
  logic        m_best_valid_q, m_runner_valid_q;
  logic [31:0] m_best_cell_q, m_runner_cell_q;
  gbt_pkg::count_t m_best_votes_q, m_runner_votes_q;
  gbt_pkg::size_t  m_best_size_q, m_runner_size_q;

  // Candidate merge_q: lane merge_q/2's best (even) or runner-up (odd).
  wire [31:0] cand_lane = 32'(merge_q) >> 1;
  wire cand_is_runner = merge_q[0];
  logic        cand_valid;
  logic [31:0] cand_cell;
  gbt_pkg::count_t cand_votes;
  gbt_pkg::size_t  cand_size;
  always_comb begin
    cand_valid = 1'b0;
    cand_cell = '0;
    cand_votes = '0;
    cand_size = '0;
    for (int k = 0; k < Lanes; k++) begin
      if (cand_lane == k) begin
        cand_valid = cand_is_runner ? l_runner_valid[k] : l_best_valid[k];
        cand_cell = cand_is_runner ? l_runner_cell[k] : l_best_cell[k];
        cand_votes = cand_is_runner ? l_runner_votes[k] : l_best_votes[k];
        cand_size = cand_is_runner ? l_runner_size[k] : l_best_size[k];
      end
    end
  end
  wire        against_valid = merge_runner_q ? m_runner_valid_q : m_best_valid_q;
  wire [31:0] against_cell = merge_runner_q ? m_runner_cell_q : m_best_cell_q;
  wire gbt_pkg::count_t against_votes = merge_runner_q ? m_runner_votes_q : m_best_votes_q;
  wire gbt_pkg::size_t  against_size = merge_runner_q ? m_runner_size_q : m_best_size_q;
  wire cand_wins = !against_valid || gbt_pkg::ranks_before(cand_cell, cand_votes, cand_size, against_cell, against_votes, against_size);
  wire merge_last = 32'(merge_q) == 2 * Lanes - 1;
  // The candidate is settled this clock: invalid, placed, or rejected by both.
  wire merge_advance = !cand_valid || cand_wins || merge_runner_q;

  always_comb begin
    state_d = state_q;
    unique case (state_q)
      StIdle, StDone: if (frame_start_i) state_d = StClear;
      StClear: if (&lane_idle) state_d = StRun;
      StRun: if (frame_end_i || end_pending_q) state_d = StDrain;
      StDrain: if (!in_valid_q && !chk_valid_q && !pixel_valid_q && !word_valid_q && !pushing_q && !(|lane_pushing) && (&lane_idle)) state_d = StLaneMerge;
      StLaneMerge: if (lane_merge_sent_q && (&lane_idle)) state_d = (Lanes == 1) ? StDone : StMerge;
      StMerge: if (Lanes == 1 || (merge_last && merge_advance)) state_d = StDone;  // constant for one lane: merge logic drops out
      default: state_d = StIdle;
    endcase
  end

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      state_q <= StIdle;
      lane_merge_sent_q <= 1'b0;
      end_pending_q <= 1'b0;
      cycles_q <= '0;
      merge_q <= '0;
      merge_runner_q <= 1'b0;
      m_best_valid_q <= 1'b0;
      m_runner_valid_q <= 1'b0;
      m_best_cell_q <= '0;
      m_runner_cell_q <= '0;
      m_best_votes_q <= '0;
      m_runner_votes_q <= '0;
      m_best_size_q <= '0;
      m_runner_size_q <= '0;
    end else begin
      state_q <= state_d;
      lane_merge_sent_q <= state_q == StLaneMerge;
      if (clear || state_q == StDrain) end_pending_q <= 1'b0;
      else if (frame_end_i && (state_q == StClear || state_q == StRun)) end_pending_q <= 1'b1;
      if (clear) begin
        cycles_q <= '0;
        merge_q <= '0;
        merge_runner_q <= 1'b0;
        m_best_valid_q <= 1'b0;
        m_runner_valid_q <= 1'b0;
      end else if (state_q != StDone && state_q != StIdle) begin
        cycles_q <= cycles_q + 1;
      end
      if (state_q == StMerge) begin
        merge_runner_q <= !merge_advance;
        if (merge_advance) merge_q <= merge_q + 1'b1;
        if (cand_valid && cand_wins) begin
          if (!merge_runner_q) begin  // the new best; the old best becomes runner-up
            m_runner_valid_q <= m_best_valid_q;
            m_runner_cell_q <= m_best_cell_q;
            m_runner_votes_q <= m_best_votes_q;
            m_runner_size_q <= m_best_size_q;
            m_best_valid_q <= 1'b1;
            m_best_cell_q <= cand_cell;
            m_best_votes_q <= cand_votes;
            m_best_size_q <= cand_size;
          end else begin
            m_runner_valid_q <= 1'b1;
            m_runner_cell_q <= cand_cell;
            m_runner_votes_q <= cand_votes;
            m_runner_size_q <= cand_size;
          end
        end
      end
    end
  end

  logic [31:0] votes_sum;
  always_comb begin
    votes_sum = '0;
    for (int k = 0; k < Lanes; k++) votes_sum += l_votes[k];
  end

  assign busy_o = state_q == StClear || state_q == StDrain || state_q == StLaneMerge || state_q == StMerge;
  assign result_valid_o = state_q == StDone;
  assign best_cell_o = (Lanes == 1) ? l_best_cell[0] : m_best_cell_q;
  assign best_votes_o = (Lanes == 1) ? l_best_votes[0] : m_best_votes_q;
  assign runner_valid_o = (Lanes == 1) ? l_runner_valid[0] : m_runner_valid_q;
  assign runner_cell_o = (Lanes == 1) ? l_runner_cell[0] : m_runner_cell_q;
  assign runner_votes_o = (Lanes == 1) ? l_runner_votes[0] : m_runner_votes_q;
  assign votes_o = votes_sum;
  assign features_o = features_q;
  assign cycles_o = cycles_q;
  assign overflow_o = overflow_q;
  assign roi_error_o = roi_error_q;

`ifndef SYNTHESIS
  // The handshake never drops or duplicates a feature: every feature taken is
  // counted exactly once as accepted, out of ROI or over capacity (checked in
  // simulation on every clock of the co-simulation).
  logic [31:0] taken_q, rejected_q;
  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      taken_q <= '0;
      rejected_q <= '0;
    end else if (clear) begin
      taken_q <= '0;
      rejected_q <= '0;
    end else begin
      taken_q <= taken_q + 32'(take);
      rejected_q <= rejected_q + 32'(chk_valid_q && !accept);
    end
  end
  /* verilator lint_off SYNCASYNCNET */  // rst_ni only quiets the checks during reset
  always_ff @(posedge clk_i) begin
    if (rst_ni && !clear) EveryFeatureCounted: assert (taken_q == features_q + rejected_q + 32'(in_valid_q) + 32'(chk_valid_q) + 32'(pixel_valid_q));
    if (rst_ni && take) TakenOnlyWhileRunning: assert (state_q == StRun);
  end
  /* verilator lint_on SYNCASYNCNET */
`endif

`ifdef FORMAL
  // Proved by hdl/formal/prove.sh voter1 and voter2 with yosys-smtbmc on a small instance,
  // together with each lane's proof (gbt_vote_lane: its environment becomes
  // an obligation here) and EveryFeatureCounted above. Assumed: a loaded,
  // valid table that is not rewritten, and ROI inputs that hold still.
  logic f_started_q = 1'b0;
  always_ff @(posedge clk_i) f_started_q <= 1'b1;
  (* anyconst *) logic [31:0] f_cell_count;
  (* anyconst *) logic [15:0] f_roi_width, f_roi_height;
  always_comb begin
    if (!f_started_q) assume (!rst_ni);
    assume (!tbl_we_i);
    assume (cell_count_i == f_cell_count && f_cell_count >= 1 && f_cell_count <= CellCapacity);
    assume (roi_width_i == f_roi_width && roi_height_i == f_roi_height);
    assume (32'(f_roi_width) * 32'(f_roi_height) <= PixelCapacity);
    assume (cnt_cell_i < CellCapacity);
    // Helpers for the induction. Between frames nothing is in flight; the
    // intake's slack: each lane's FIFO has room for every feature in flight
    // towards it, and one clock after room_all_q was set, for one more.
    if (rst_ni) begin
      if (state_q == StIdle || state_q == StDone || state_q == StMerge)
        assert ((&lane_idle) && !in_valid_q && !chk_valid_q && !pixel_valid_q && !word_valid_q && !pushing_q && !(|lane_pushing));
      if (state_q != StLaneMerge) assert (!(|lane_merging));
      if (state_q == StLaneMerge && !lane_merge_sent_q) assert (&lane_idle);
      if (state_q == StLaneMerge)
        assert (!in_valid_q && !chk_valid_q && !pixel_valid_q && !word_valid_q && !pushing_q && !(|lane_pushing));
      if (state_q == StClear)
        assert (!in_valid_q && !chk_valid_q && !pixel_valid_q && !word_valid_q && !pushing_q && !(|lane_pushing));
      for (int k = 0; k < Lanes; k++) begin
        assert (32'(lane_free[k]) >= 32'(in_valid_q) + 32'(chk_valid_q) + 32'(pixel_valid_q) + 32'(word_valid_q)
                                    + 32'(pushing_q) + 32'(lane_pushing[k]));
        if (room_all_q) assert (32'(lane_free[k]) >= 7);
      end
    end
    // Every offsets word read for a pixel holds ranges inside each lane's refs.
    for (int k = 0; k < Lanes; k++) begin
      if (word_valid_q)
        assume (32'(offsets_word[k*RangeWidth+RangeCountWidth +: OffsetWidth]) + 32'(offsets_word[k*RangeWidth +: RangeCountWidth])
                <= RefsPerLane);
    end
  end
`endif

endmodule

`default_nettype wire
