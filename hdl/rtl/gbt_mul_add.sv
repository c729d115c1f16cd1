// gbt_mul_add — y = a * b + c over WidthBits bits (modulo 2^WidthBits), in
// fabric adders rather than a DSP, two clocks of latency, one result per
// clock.
//
// The intake uses it for the pixel index (row * roi_width + col) so that all
// of a UP5K's eight multipliers stay with the voting lane's ranking, which
// needs eight.
//
// Pipeline: the WidthBits partial products a[i] ? b << i : 0 and c are
// summed in groups of four (two adder levels, balanced), the group sums
// registered (clock 1), then summed in a balanced tree into y_o's register
// (clock 2). Two adder levels per clock for WidthBits <= 15.
`default_nettype none

module gbt_mul_add #(
  parameter int unsigned WidthBits = 12,
  localparam int unsigned Terms = WidthBits + 1,
  localparam int unsigned Groups = (Terms + 3) / 4
) (
  input  logic                 clk_i,
  input  logic [WidthBits-1:0] a_i,
  input  logic [WidthBits-1:0] b_i,
  input  logic [WidthBits-1:0] c_i,
  output logic [WidthBits-1:0] y_o
);

  logic [WidthBits-1:0] term [Groups * 4];
  for (genvar i = 0; i < Groups * 4; i++) begin : g_term
    if (i < WidthBits) begin : g_partial
      assign term[i] = a_i[i] ? (b_i << i) : '0;
    end else if (i == WidthBits) begin : g_addend
      assign term[i] = c_i;
    end else begin : g_pad
      assign term[i] = '0;
    end
  end

  // Clock 1: each group of four as (t0 + t1) + (t2 + t3).
  logic [WidthBits-1:0] group_q [Groups];
  for (genvar g = 0; g < Groups; g++) begin : g_group
    always_ff @(posedge clk_i) begin
      group_q[g] <= (term[4*g] + term[4*g+1]) + (term[4*g+2] + term[4*g+3]);
    end
  end

  // Clock 2: the group sums, pairwise, level by level.
  localparam int unsigned Padded = 1 << $clog2(Groups);
  // A binary tree in one array, leaves at [Padded-1 ...]: node n reads only
  // nodes 2n+1 and 2n+2, so there is no loop, but Verilator sees the array
  // feeding itself and warns (UNOPTFLAT); the waiver is for that.
  /* verilator lint_off UNOPTFLAT */
  logic [WidthBits-1:0] level [2 * Padded - 1];
  /* verilator lint_on UNOPTFLAT */
  for (genvar n = 0; n < Padded; n++) begin : g_leaf
    if (n < Groups) begin : g_sum
      assign level[Padded - 1 + n] = group_q[n];
    end else begin : g_zero
      assign level[Padded - 1 + n] = '0;
    end
  end
  for (genvar n = 0; n < Padded - 1; n++) begin : g_node
    assign level[n] = level[2*n+1] + level[2*n+2];
  end
  always_ff @(posedge clk_i) y_o <= level[0];

endmodule

`default_nettype wire
