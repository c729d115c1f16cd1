// gbt_voter_axil — gbt_voter behind an AXI4-Lite slave (32-bit data), for a
// CPU that loads the table, feeds features and reads results.
//
// Register map (byte offsets; R = read, W = write):
//   0x00 W  CTRL          bit 0: frame start, bit 1: frame end (pulses)
//   0x04 R  STATUS        bit 0 busy, 1 result valid, 2 overflow, 3 ROI error, 4 feature ready
//   0x08 W  FEATURE       {row[31:16], col[15:0]}; the write response waits
//                         until the voter takes the feature (back-pressure)
//   0x0C RW CELL_COUNT    cells of the loaded table
//   0x10 RW ROI           {height[31:16], width[15:0]}
//   0x14 R  BEST_CELL     0x18 R BEST_VOTES
//   0x1C R  RUNNER_CELL   0xFFFFFFFF when there is none; 0x20 R RUNNER_VOTES
//   0x24 R  VOTES         0x28 R FEATURES   0x2C R CYCLES
//   0x30 W  CNT_CELL      0x34 R CNT_DATA: counter of CNT_CELL (idle or done)
//   0x38 W  TBL_SELECT    {lane[10:8], memory[1:0]}: 0 offsets, 1 refs, 2 sizes
//   0x3C W  TBL_ADDR
//   0x40..0x4C W TBL_DATA0..3  data bits [31:0] .. [127:96]
//   0x50 W  TBL_COMMIT    writes TBL_DATA to TBL_SELECT/TBL_ADDR (while idle)
//   0x54 R  ID            0x47425431 ("GBT1")
//   0x58 R  CONFIG        {Lanes[31:24], log2 CellCapacity[23:16], log2 PixelCapacity[15:8], log2 RefsPerLane[7:0]}
// Unmapped addresses read 0 and ignore writes (OKAY responses).
//
// Handshake: one write and one read in flight. A write completes when both
// AW and W have arrived; its B response follows one clock later (or once the
// feature is taken, for FEATURE). A read's R response follows AR by one clock.
`default_nettype none

module gbt_voter_axil #(
  parameter int unsigned Lanes = 1,
  parameter int unsigned CellCapacity = 128,
  parameter int unsigned PixelCapacity = 4096,
  parameter int unsigned RefsPerLane = 32768,
  parameter int unsigned MaxFeaturesPerFrame = 65535
) (
  input  logic        clk_i,
  input  logic        rst_ni,
  input  logic        s_axil_awvalid,
  output logic        s_axil_awready,
  input  logic [7:0]  s_axil_awaddr,
  input  logic        s_axil_wvalid,
  output logic        s_axil_wready,
  input  logic [31:0] s_axil_wdata,
  /* verilator lint_off UNUSEDSIGNAL */
  input  logic [3:0]  s_axil_wstrb,   // full-word writes only: strobes are not used
  /* verilator lint_on UNUSEDSIGNAL */
  output logic        s_axil_bvalid,
  input  logic        s_axil_bready,
  output logic [1:0]  s_axil_bresp,
  input  logic        s_axil_arvalid,
  output logic        s_axil_arready,
  input  logic [7:0]  s_axil_araddr,
  output logic        s_axil_rvalid,
  input  logic        s_axil_rready,
  output logic [31:0] s_axil_rdata,
  output logic [1:0]  s_axil_rresp
);

  localparam int unsigned CellsPerLane = (CellCapacity + Lanes - 1) / Lanes;
  localparam int unsigned RangeWidth = $clog2(RefsPerLane + 1) + $clog2(CellsPerLane + 1);
  localparam int unsigned TableDataWidth = (Lanes * RangeWidth > 32) ? Lanes * RangeWidth : 32;
  localparam int unsigned LaneWidth = (Lanes > 1) ? $clog2(Lanes) : 1;

  // ---------------------------------------------------------------- voter
  logic        frame_start, frame_end, busy, feat_valid, feat_ready, result_valid, runner_valid, overflow, roi_error;
  logic [15:0] feat_col_q, feat_row_q;
  logic [31:0] cell_count_q, best_cell, runner_cell, votes, features, cycles, cnt_cell_q;
  logic [15:0] roi_width_q, roi_height_q, best_votes, runner_votes, cnt_data;
  logic        tbl_we;
  logic [1:0]  tbl_sel_q;
  logic [31:0] tbl_addr_q;
  // Registers hold whole written fields; the voter takes the bits it uses
  // (its lane index width, its table data width).
  /* verilator lint_off UNUSEDSIGNAL */
  logic [2:0]  tbl_lane_q;
  logic [127:0] tbl_data_q;
  /* verilator lint_on UNUSEDSIGNAL */

  gbt_voter #(.Lanes(Lanes), .CellCapacity(CellCapacity), .PixelCapacity(PixelCapacity), .RefsPerLane(RefsPerLane),
              .MaxFeaturesPerFrame(MaxFeaturesPerFrame)) u_voter (
    .clk_i, .rst_ni,
    .cell_count_i(cell_count_q), .roi_width_i(roi_width_q), .roi_height_i(roi_height_q),
    .frame_start_i(frame_start), .frame_end_i(frame_end), .busy_o(busy),
    .feat_valid_i(feat_valid), .feat_ready_o(feat_ready), .feat_col_i(feat_col_q), .feat_row_i(feat_row_q),
    .result_valid_o(result_valid), .best_cell_o(best_cell), .best_votes_o(best_votes), .runner_valid_o(runner_valid),
    .runner_cell_o(runner_cell), .runner_votes_o(runner_votes), .votes_o(votes), .features_o(features), .cycles_o(cycles),
    .overflow_o(overflow), .roi_error_o(roi_error),
    .tbl_we_i(tbl_we), .tbl_sel_i(tbl_sel_q), .tbl_lane_i(tbl_lane_q[LaneWidth-1:0]), .tbl_addr_i(tbl_addr_q),
    .tbl_data_i(tbl_data_q[TableDataWidth-1:0]),
    .cnt_cell_i(cnt_cell_q), .cnt_data_o(cnt_data)
  );

  // ---------------------------------------------------------------- writes
  logic       aw_held_q, w_held_q, feat_pending_q;
  logic [7:0] awaddr_q;
  logic [31:0] wdata_q;

  assign s_axil_awready = !aw_held_q && !s_axil_bvalid;
  assign s_axil_wready  = !w_held_q && !s_axil_bvalid;
  assign s_axil_bresp   = 2'b00;
  assign feat_valid     = feat_pending_q;
  wire do_write = aw_held_q && w_held_q && !s_axil_bvalid && !feat_pending_q;

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      aw_held_q <= 1'b0;
      w_held_q <= 1'b0;
      awaddr_q <= '0;
      wdata_q <= '0;
      s_axil_bvalid <= 1'b0;
      feat_pending_q <= 1'b0;
      feat_col_q <= '0;
      feat_row_q <= '0;
      frame_start <= 1'b0;
      frame_end <= 1'b0;
      tbl_we <= 1'b0;
      cell_count_q <= 32'd1;
      roi_width_q <= 16'd1;
      roi_height_q <= 16'd1;
      cnt_cell_q <= '0;
      tbl_sel_q <= '0;
      tbl_lane_q <= '0;
      tbl_addr_q <= '0;
      tbl_data_q <= '0;
    end else begin
      frame_start <= 1'b0;
      frame_end <= 1'b0;
      tbl_we <= 1'b0;
      if (s_axil_awvalid && s_axil_awready) begin
        aw_held_q <= 1'b1;
        awaddr_q <= s_axil_awaddr;
      end
      if (s_axil_wvalid && s_axil_wready) begin
        w_held_q <= 1'b1;
        wdata_q <= s_axil_wdata;
      end
      if (s_axil_bvalid && s_axil_bready) s_axil_bvalid <= 1'b0;
      if (feat_pending_q && feat_ready) begin
        feat_pending_q <= 1'b0;
        s_axil_bvalid <= 1'b1;
      end
      if (do_write) begin
        aw_held_q <= 1'b0;
        w_held_q <= 1'b0;
        s_axil_bvalid <= awaddr_q != 8'h08;
        unique case (awaddr_q)
          8'h00: begin
            frame_start <= wdata_q[0];
            frame_end <= wdata_q[1];
          end
          8'h08: begin
            feat_pending_q <= 1'b1;
            feat_col_q <= wdata_q[15:0];
            feat_row_q <= wdata_q[31:16];
          end
          8'h0C: cell_count_q <= wdata_q;
          8'h10: {roi_height_q, roi_width_q} <= wdata_q;
          8'h30: cnt_cell_q <= wdata_q;
          8'h38: {tbl_lane_q, tbl_sel_q} <= {wdata_q[10:8], wdata_q[1:0]};
          8'h3C: tbl_addr_q <= wdata_q;
          8'h40: tbl_data_q[31:0] <= wdata_q;
          8'h44: tbl_data_q[63:32] <= wdata_q;
          8'h48: tbl_data_q[95:64] <= wdata_q;
          8'h4C: tbl_data_q[127:96] <= wdata_q;
          8'h50: tbl_we <= 1'b1;
          default: ;
        endcase
      end
    end
  end

  // ----------------------------------------------------------------- reads
  assign s_axil_arready = !s_axil_rvalid;
  assign s_axil_rresp = 2'b00;

  logic [31:0] rdata;
  always_comb begin
    unique case (s_axil_araddr)
      8'h04: rdata = {27'd0, feat_ready, roi_error, overflow, result_valid, busy};
      8'h0C: rdata = cell_count_q;
      8'h10: rdata = {roi_height_q, roi_width_q};
      8'h14: rdata = best_cell;
      8'h18: rdata = {16'd0, best_votes};
      8'h1C: rdata = runner_valid ? runner_cell : 32'hFFFF_FFFF;
      8'h20: rdata = {16'd0, runner_votes};
      8'h24: rdata = votes;
      8'h28: rdata = features;
      8'h2C: rdata = cycles;
      8'h34: rdata = {16'd0, cnt_data};
      8'h54: rdata = 32'h4742_5431;
      8'h58: rdata = {8'(Lanes), 8'($clog2(CellCapacity)), 8'($clog2(PixelCapacity)), 8'($clog2(RefsPerLane))};
      default: rdata = '0;
    endcase
  end

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      s_axil_rvalid <= 1'b0;
      s_axil_rdata <= '0;
    end else if (s_axil_arvalid && s_axil_arready) begin
      s_axil_rvalid <= 1'b1;
      s_axil_rdata <= rdata;
    end else if (s_axil_rvalid && s_axil_rready) begin
      s_axil_rvalid <= 1'b0;
    end
  end

endmodule

`default_nettype wire
