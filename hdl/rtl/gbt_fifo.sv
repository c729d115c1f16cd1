// gbt_fifo — small synchronous FIFO (registers), first-word fall-through.
//
// push_i with !full_o stores wdata_i; rdata_o shows the head whenever
// !empty_o, and pop_i removes it. A push and a pop may happen in one cycle.
// free_o counts the free slots (the voter's intake uses it for slack).
`default_nettype none

module gbt_fifo #(
  parameter int unsigned Depth = 8,       // a power of two
  parameter int unsigned WidthBits = 32,
  localparam int unsigned PtrWidth = $clog2(Depth)
) (
  input  logic                 clk_i,
  input  logic                 rst_ni,
  input  logic                 push_i,
  input  logic [WidthBits-1:0] wdata_i,
  input  logic                 pop_i,
  output logic [WidthBits-1:0] rdata_o,
  output logic                 empty_o,
  output logic                 full_o,
  output logic [PtrWidth:0]    free_o
);

  logic [WidthBits-1:0] mem_q [Depth];
  logic [PtrWidth-1:0]  rd_q, wr_q;
  logic [PtrWidth:0]    used_q;
  logic                 empty_q;  // used_q == 0, registered: the consumer's pop depends on it

  assign empty_o = empty_q;
  assign full_o  = (used_q == (PtrWidth + 1)'(Depth));
  assign free_o  = (PtrWidth + 1)'(Depth) - used_q;
  assign rdata_o = mem_q[rd_q];

  wire do_push = push_i && !full_o;
  wire do_pop  = pop_i && !empty_o;

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      rd_q <= '0;
      wr_q <= '0;
      used_q <= '0;
      empty_q <= 1'b1;
    end else begin
      if (do_push) wr_q <= wr_q + 1'b1;
      if (do_pop) rd_q <= rd_q + 1'b1;
      used_q <= used_q + (PtrWidth + 1)'(do_push) - (PtrWidth + 1)'(do_pop);
      empty_q <= !do_push && (do_pop ? used_q == (PtrWidth + 1)'(1) : empty_q);
    end
  end

  always_ff @(posedge clk_i) begin
    if (do_push) mem_q[wr_q] <= wdata_i;
  end

`ifdef FORMAL
  // Invariants that hold whatever the data, proved wherever the FIFO is
  // instantiated in a proof (hdl/formal/fifo.sh, hdl/formal/lane.sh).
  always_comb begin
    if (rst_ni) begin
      assert (used_q <= (PtrWidth + 1)'(Depth));
      assert (empty_q == (used_q == '0));
      assert (wr_q == PtrWidth'(rd_q + used_q[PtrWidth-1:0]));
    end
  end
`endif

`ifdef FORMAL_FIFO
  // Proved by hdl/formal/fifo.sh with yosys-smtbmc (BMC and k-induction),
  // with the FIFO as the top. The FIFO never looks at its data, so proving it
  // with each word equal to its push's sequence number covers any data:
  // every word comes out once, in the order it went in, and the occupancy is
  // pushes minus pops.
  logic [WidthBits-1:0] f_pushed_q, f_popped_q;
  // The run starts in reset.
  logic f_started_q = 1'b0;
  always_ff @(posedge clk_i) f_started_q <= 1'b1;
  always_comb if (!f_started_q) assume (!rst_ni);
  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      f_pushed_q <= '0;
      f_popped_q <= '0;
    end else begin
      if (do_push) f_pushed_q <= f_pushed_q + 1'b1;
      if (do_pop) f_popped_q <= f_popped_q + 1'b1;
    end
  end
  always_comb begin
    if (rst_ni) begin
      assume (wdata_i == f_pushed_q);
      assert (f_pushed_q - f_popped_q == WidthBits'(used_q));  // at full width, not modulo the depth
      if (!empty_o) assert (rdata_o == f_popped_q);
    end
  end
  // Every occupied slot holds the word pushed that many places after the head.
  genvar f_slot;
  for (f_slot = 0; f_slot < Depth; f_slot = f_slot + 1) begin : g_f_slot
    always_comb begin
      if (rst_ni && (PtrWidth + 1)'(f_slot) < used_q)
        assert (mem_q[PtrWidth'(rd_q + PtrWidth'(f_slot))] == f_popped_q + WidthBits'(f_slot));
    end
  end
`endif

`ifndef SYNTHESIS
  /* verilator lint_off SYNCASYNCNET */  // rst_ni only quiets the check during reset
  always_ff @(posedge clk_i) begin
    if (rst_ni) begin
      Occupancy: assert (used_q <= (PtrWidth + 1)'(Depth));
      EmptyFlag: assert (empty_q == (used_q == '0));
    end
  end
  /* verilator lint_on SYNCASYNCNET */
`endif

endmodule

`default_nettype wire
