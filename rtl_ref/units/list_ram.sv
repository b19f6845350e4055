// ListRam: an on-chip list of the early-visibility unit, one write port (tile fetch) and one
// synchronous read port (one clock of read latency). Synthesis keeps it a black box
// (rtl_ref/synth): a real unit takes an SRAM macro, not flip-flops.
module ListRam #(
    parameter int DEPTH = 256,
    parameter int WIDTH = 32,
    parameter int AW = $clog2(DEPTH)
) (
    input  wire             clk,
    input  wire             we,
    input  wire [AW-1:0]    waddr,
    input  wire [WIDTH-1:0] wdata,
    input  wire [AW-1:0]    raddr,
    output reg  [WIDTH-1:0] rdata
);
  reg [WIDTH-1:0] mem[0:DEPTH-1];
  always @(posedge clk) begin
    if (we) mem[waddr] <= wdata;
    rdata <= mem[raddr];
  end
endmodule
