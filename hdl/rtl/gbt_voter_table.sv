// gbt_voter_table — gbt_voter sized for one table: the drop-in block for an
// FPGA design. `gabarit tables export-hdl T --out DIR --lanes N` writes
// DIR/gabarit_table_pkg.sv (compile it before this file) and the memory
// images. Two ways to get the table in:
//   - InitPrefix = "DIR/": memories preloaded by the bitstream ($readmemh).
//     Block RAM only: iCE40 SPRAM cannot be preloaded.
//   - InitPrefix = "": loaded at boot through the tbl_* port (e.g. by an MCU
//     over gbt_voter_axil), which lets yosys put the table in SPRAM.
// The table description inputs of gbt_voter are tied to the package's
// constants, so the ROI check and the pixel-index multiply reduce to
// constants. Ports, handshake and timing are gbt_voter's.
`default_nettype none

module gbt_voter_table #(
  parameter InitPrefix = "",  // a string: "<export dir>/", or "" to load through tbl_*
  parameter int unsigned MaxFeaturesPerFrame = 65535,
  localparam int unsigned TableDataWidth =
      (gabarit_table_pkg::Lanes * (gabarit_table_pkg::OffsetWidth + gabarit_table_pkg::RangeCountWidth) > 32)
          ? gabarit_table_pkg::Lanes * (gabarit_table_pkg::OffsetWidth + gabarit_table_pkg::RangeCountWidth) : 32
) (
  input  logic clk_i,
  input  logic rst_ni,
  input  logic frame_start_i,
  input  logic frame_end_i,
  output logic busy_o,
  input  logic        feat_valid_i,
  output logic        feat_ready_o,
  input  logic [15:0] feat_col_i,
  input  logic [15:0] feat_row_i,
  output logic        result_valid_o,
  output logic [31:0] best_cell_o,
  output logic [15:0] best_votes_o,
  output logic        runner_valid_o,
  output logic [31:0] runner_cell_o,
  output logic [15:0] runner_votes_o,
  output logic [31:0] votes_o,
  output logic [31:0] features_o,
  output logic [31:0] cycles_o,
  output logic        overflow_o,
  output logic        roi_error_o,
  input  logic [31:0] cnt_cell_i,
  output logic [15:0] cnt_data_o,
  input  logic        tbl_we_i,
  input  logic [1:0]  tbl_sel_i,
  input  logic [2:0]  tbl_lane_i,
  input  logic [31:0] tbl_addr_i,
  input  logic [TableDataWidth-1:0] tbl_data_i
);

  localparam int unsigned LaneWidth = (gabarit_table_pkg::Lanes > 1) ? $clog2(gabarit_table_pkg::Lanes) : 1;

  gbt_voter #(
    .Lanes(gabarit_table_pkg::Lanes),
    .CellCapacity(gabarit_table_pkg::CellCapacity),
    .PixelCapacity(gabarit_table_pkg::PixelCapacity),
    .RefsPerLane(gabarit_table_pkg::RefsPerLane),
    .MaxRangeCount(gabarit_table_pkg::MaxRangeCount),
    .MaxFeaturesPerFrame(MaxFeaturesPerFrame),
    .InitPrefix(InitPrefix)
  ) u_voter (
    .clk_i, .rst_ni,
    .cell_count_i(32'(gabarit_table_pkg::CellCount)),
    .roi_width_i(16'(gabarit_table_pkg::RoiWidth)),
    .roi_height_i(16'(gabarit_table_pkg::RoiHeight)),
    .frame_start_i, .frame_end_i, .busy_o,
    .feat_valid_i, .feat_ready_o, .feat_col_i, .feat_row_i,
    .result_valid_o, .best_cell_o, .best_votes_o, .runner_valid_o, .runner_cell_o, .runner_votes_o,
    .votes_o, .features_o, .cycles_o, .overflow_o, .roi_error_o,
    .tbl_we_i, .tbl_sel_i, .tbl_lane_i(tbl_lane_i[LaneWidth-1:0]), .tbl_addr_i, .tbl_data_i,
    .cnt_cell_i, .cnt_data_o
  );

endmodule

`default_nettype wire
