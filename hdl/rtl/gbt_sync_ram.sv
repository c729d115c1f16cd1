// gbt_sync_ram — one read port, one write port, synchronous, read-first.
//
//   cycle t:   raddr_i presented (re implied), waddr_i/wdata_i/we_i presented
//   cycle t+1: rdata_o = mem[raddr] as it was *before* the write of cycle t
//
// Simulated read-first (a read and a write of the same address in one cycle
// return the old word); synthesised with the collision left unspecified
// (no_rw_check, below), which the voter tolerates. This
// is the block-RAM template yosys maps to iCE40 EBR and Verilator simulates
// directly. InitFile, when not empty, is loaded with $readmemh.
//
// SinglePort = 1: reads and writes share one address (the write address while
// we_i is high, and rdata_o then holds its previous value) — the form yosys
// maps to the UltraPlus's 256-kbit SPRAMs. Only for memories that are never
// read and written in the same cycle (the voter's table memories, written
// while idle).
`default_nettype none

module gbt_sync_ram #(
  parameter int unsigned Depth = 256,
  parameter int unsigned WidthBits = 16,
  parameter InitFile = "",  // a string (untyped: yosys 0.23 has no string parameters)
  parameter bit SinglePort = 1'b0,
  localparam int unsigned AddrWidth = (Depth > 1) ? $clog2(Depth) : 1
) (
  input  logic                 clk_i,
  input  logic [AddrWidth-1:0] raddr_i,
  output logic [WidthBits-1:0] rdata_o,
  input  logic                 we_i,
  input  logic [AddrWidth-1:0] waddr_i,
  input  logic [WidthBits-1:0] wdata_i,
  // Formal proofs only (hdl/formal): peek_data_o = mem[peek_addr_i],
  // combinational, so a proof can state what a word holds. Tie peek_addr_i
  // to '0 and leave peek_data_o open; outside `FORMAL` it is constant zero.
  /* verilator lint_off UNUSEDSIGNAL */
  input  logic [AddrWidth-1:0] peek_addr_i,
  /* verilator lint_on UNUSEDSIGNAL */
  output logic [WidthBits-1:0] peek_data_o
);

  // no_rw_check: on an FPGA, a read that collides with a write to the same
  // word may return either word, so yosys adds no bypass logic for the
  // read-first behaviour. The voter never uses such a word: a collision is a
  // vote reading the counter the previous vote is writing, and the
  // forwarding replaces it (the lane's formal proof covers this). Verilator
  // still simulates read-first.
  (* no_rw_check *)
  logic [WidthBits-1:0] mem [Depth];

  // No zeroing loop: FPGA block RAMs power up as zero (and yosys would unroll
  // it word by word); the voter clears its counters itself at frame start.
  initial begin
    if (InitFile != "") $readmemh(InitFile, mem);
  end

  if (SinglePort) begin : g_single_port
    wire [AddrWidth-1:0] addr = we_i ? waddr_i : raddr_i;
    always_ff @(posedge clk_i) begin
      if (we_i) mem[addr] <= wdata_i;
      else rdata_o <= mem[addr];
    end
  end else begin : g_dual_port
    always_ff @(posedge clk_i) begin
      if (we_i) mem[waddr_i] <= wdata_i;
      rdata_o <= mem[raddr_i];
    end
  end

`ifdef FORMAL
  assign peek_data_o = mem[peek_addr_i];
`else
  assign peek_data_o = '0;
`endif

`ifndef SYNTHESIS
  // Every access stays inside the memory (Depth need not be a power of two).
  always_ff @(posedge clk_i) begin
    ReadInRange: assert (32'(raddr_i) < Depth);
    if (we_i) WriteInRange: assert (32'(waddr_i) < Depth);
  end
`endif

endmodule

`default_nettype wire
