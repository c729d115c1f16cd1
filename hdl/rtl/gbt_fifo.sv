// gbt_fifo — small synchronous FIFO (registers), first-word fall-through.
//
// push_i with !full_o stores wdata_i; rdata_o shows the head whenever
// !empty_o, and pop_i removes it. A push and a pop may happen in one cycle.
// free_o counts the free slots (the voter's intake uses it for slack).
//
// A shifting FIFO: the head is always slot 0 (so rdata_o comes straight from
// flip-flops, with no read multiplexer), a pop moves every slot one place
// towards the head, and a push writes the first free slot, found from a
// one-hot tail register. Every slot's next value is a 3-input choice.
`default_nettype none

module gbt_fifo #(
  parameter int unsigned Depth = 8,
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
  logic [PtrWidth:0]    used_q;
  logic                 empty_q;   // used_q == 0, registered: the consumer's pop depends on it
  logic [Depth:0]       tail_q;    // one-hot: bit used_q set

  assign empty_o = empty_q;
  assign full_o  = tail_q[Depth];
  assign free_o  = (PtrWidth + 1)'(Depth) - used_q;
  assign rdata_o = mem_q[0];

  wire do_push = push_i && !full_o;
  wire do_pop  = pop_i && !empty_o;

  always_ff @(posedge clk_i or negedge rst_ni) begin
    if (!rst_ni) begin
      used_q <= '0;
      empty_q <= 1'b1;
      tail_q <= (Depth + 1)'(1);
    end else begin
      used_q <= used_q + (PtrWidth + 1)'(do_push) - (PtrWidth + 1)'(do_pop);
      empty_q <= !do_push && (do_pop ? tail_q[1] : empty_q);
      if (do_push && !do_pop) tail_q <= tail_q << 1;
      else if (do_pop && !do_push) tail_q <= tail_q >> 1;
    end
  end

  // Slot i takes the pushed word if it is the first free slot after this
  // clock's pop, else its successor on a pop, else keeps its word.
  for (genvar i = 0; i < Depth; i++) begin : g_slot
    wire write_here = do_push && (do_pop ? tail_q[i + 1] : tail_q[i]);
    always_ff @(posedge clk_i) begin
      if (write_here) mem_q[i] <= wdata_i;
      else if (do_pop) mem_q[i] <= (i + 1 < Depth) ? mem_q[(i + 1) % Depth] : mem_q[i];
    end
  end

`ifdef FORMAL
  // Invariants that hold whatever the data, proved wherever the FIFO is
  // instantiated in a proof (hdl/formal/prove.sh fifo, lane, voter*).
  always_comb begin
    if (rst_ni) begin
      assert (used_q <= (PtrWidth + 1)'(Depth));
      assert (empty_q == (used_q == '0));
      assert (tail_q == (Depth + 1)'(1) << used_q);
    end
  end
`endif

`ifdef FORMAL_FIFO
  // Proved by hdl/formal/prove.sh fifo with yosys-smtbmc (BMC and
  // k-induction), with the FIFO as the top. The FIFO never looks at its
  // data, so proving it with each word equal to its push's sequence number
  // covers any data: every word comes out once, in the order it went in, and
  // the occupancy is pushes minus pops.
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
      if (rst_ni && (PtrWidth + 1)'(f_slot) < used_q) assert (mem_q[f_slot] == f_popped_q + WidthBits'(f_slot));
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
