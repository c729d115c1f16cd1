// gbt_pkg — shared constants and the ranking rule of the gabarit voter.
//
// The ranking mirrors kernel/include/gabarit/voter.hpp bit for bit: cell a
// ranks before cell b iff votes_a * size_b > votes_b * size_a, or the
// products are equal and a has the lower cell index. Sizes are stored already
// clamped to >= 1 (tables/export-hdl does it), so no clamp is needed here.
`default_nettype none

package gbt_pkg;

  parameter int unsigned CounterWidthBits = 16;  // the kernel's VoteCounter
  parameter int unsigned SizeWidthBits    = 16;  // stencil sizes, clamped to [1, 65535] by the export

  typedef logic [CounterWidthBits-1:0] count_t;
  typedef logic [SizeWidthBits-1:0]    size_t;

  // a ranks before b (strictly).
  function automatic logic ranks_before(input logic [31:0] cell_a, input count_t votes_a, input size_t size_a,
                                        input logic [31:0] cell_b, input count_t votes_b, input size_t size_b);
    logic [CounterWidthBits+SizeWidthBits-1:0] lhs, rhs;
    lhs = votes_a * size_b;
    rhs = votes_b * size_a;
    // One wide comparison instead of (lhs > rhs) || (lhs == rhs && a < b): the
    // same order ({lhs, ~a} > {rhs, ~b}), but a single carry chain on an
    // FPGA. Assigned to the function name: yosys 0.23 reads no `return`.
    ranks_before = {lhs, ~cell_a} > {rhs, ~cell_b};
  endfunction

endpackage

`default_nettype wire
