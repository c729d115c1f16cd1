// gbt_synth_top — a pin-light harness for synthesis and place-and-route
// reports only (the UP5K's sg48 package has 39 I/Os; gbt_voter has ~200
// ports). Inputs come from a shift register fed by one pin, and every output
// is folded into one registered pin, so no logic is optimised away and the
// table memories stay writable (and mappable to SPRAM).
`default_nettype none

module gbt_synth_top (
  input  logic clk,
  input  logic rst_n,
  input  logic sin,
  input  logic frame_start,
  input  logic frame_end,
  input  logic feat_valid,
  input  logic tbl_we,
  output logic feat_ready,
  output logic result_valid,
  output logic busy,
  output logic sout
);

  localparam int unsigned DataWidth = 128;
  logic [255:0] shift_q;
  always_ff @(posedge clk) shift_q <= {shift_q[254:0], sin};

  logic [31:0] best_cell, runner_cell, votes, features, cycles;
  logic [15:0] best_votes, runner_votes, cnt_data;
  logic runner_valid, overflow, roi_error;

  gbt_voter_table #(.InitPrefix("")) u_voter (
    .clk_i(clk), .rst_ni(rst_n),
    .frame_start_i(frame_start), .frame_end_i(frame_end), .busy_o(busy),
    .feat_valid_i(feat_valid), .feat_ready_o(feat_ready), .feat_col_i(shift_q[15:0]), .feat_row_i(shift_q[31:16]),
    .result_valid_o(result_valid), .best_cell_o(best_cell), .best_votes_o(best_votes), .runner_valid_o(runner_valid),
    .runner_cell_o(runner_cell), .runner_votes_o(runner_votes), .votes_o(votes), .features_o(features), .cycles_o(cycles),
    .overflow_o(overflow), .roi_error_o(roi_error),
    .cnt_cell_i(shift_q[63:32]), .cnt_data_o(cnt_data),
    .tbl_we_i(tbl_we), .tbl_sel_i(shift_q[65:64]), .tbl_lane_i(shift_q[68:66]), .tbl_addr_i(shift_q[100:69]),
    .tbl_data_i(shift_q[255:256 - $bits(u_voter.tbl_data_i)])
  );

  always_ff @(posedge clk) begin
    sout <= ^{best_cell, runner_cell, votes, features, cycles, best_votes, runner_votes, cnt_data, runner_valid, overflow, roi_error};
  end

endmodule

`default_nettype wire
