// gbt_sync_ram — one read port, one write port, synchronous, read-first.
//
//   cycle t:   raddr_i presented (re implied), waddr_i/wdata_i/we_i presented
//   cycle t+1: rdata_o = mem[raddr] as it was *before* the write of cycle t
//
// Read-first behaviour is what the voter's forwarding logic assumes (a read
// and a write of the same address in one cycle returns the old word). This
// is the block-RAM template yosys maps to iCE40 EBR and Verilator simulates
// directly. InitFile, when not empty, is loaded with $readmemh.
`default_nettype none

module gbt_sync_ram #(
  parameter int unsigned Depth = 256,
  parameter int unsigned WidthBits = 16,
  parameter string InitFile = "",
  localparam int unsigned AddrWidth = (Depth > 1) ? $clog2(Depth) : 1
) (
  input  logic                 clk_i,
  input  logic [AddrWidth-1:0] raddr_i,
  output logic [WidthBits-1:0] rdata_o,
  input  logic                 we_i,
  input  logic [AddrWidth-1:0] waddr_i,
  input  logic [WidthBits-1:0] wdata_i
);

  logic [WidthBits-1:0] mem [Depth];

  initial begin
    for (int unsigned i = 0; i < Depth; i++) mem[i] = '0;
    if (InitFile != "") $readmemh(InitFile, mem);
  end

  always_ff @(posedge clk_i) begin
    if (we_i) mem[waddr_i] <= wdata_i;
    rdata_o <= mem[raddr_i];
  end

`ifdef FORMAL
  // Every access stays inside the memory (Depth need not be a power of two).
  always_ff @(posedge clk_i) begin
    assert (32'(raddr_i) < Depth);
    if (we_i) assert (32'(waddr_i) < Depth);
  end
`endif

endmodule

`default_nettype wire
