// TileSequencer: walks one pass of a tile's job from the on-chip lists and issues
// triangle x silhouette-edge pairs to LANES PairReject lanes, one row of LANES edges a clock.
//
// The lists: triangles (TRI_CAP entries: z_max) and edges (EDGE_CAP entries: z_min, sorted by
// z_min ascending, ties in silhouette order: the order of the analytic resolver). The edge list
// is banked LANES ways (edge i in bank i % LANES), so a row of LANES edges reads in one clock.
// Per triangle, rows 0, 1, ... issue every edge before the first whose z_min > the triangle's
// z_max (SVGPU §3.2.1 test 6; that edge and all later ones are never issued). Stage A reads
// row r, stage B compares and issues it; A runs ahead by one row, so a triangle that stops on
// test 6 before its last row costs one more clock (the row A fetched is dropped).
//   clocks per triangle = rows read by A = min(floor(p / LANES) + 2, rows) when it stops on
//   test 6 after p pairs, else rows = max(1, ceil(n_edges / LANES)); the pass's last
//   triangle stopping on test 6 costs floor(p / LANES) + 1 (`done` comes with that row).
// A pass ends 2 clocks after its last row (stage B, then `done`).
//
// Overflow: a tile with more than TRI_CAP triangles or EDGE_CAP edges runs in passes, each
// loaded by tile fetch through the write ports (one entry per list per clock): triangle chunks
// outer, edge chunks inner (rtl_ref/README.md). A triangle that stopped in an earlier edge
// chunk stops on the first edge of every later chunk (the edges are sorted).
//
// Widths: z: ZW <= 32 bits unsigned (model/geom depth); indices TIW / EIW bits.
module TileSequencer #(
    parameter int LANES = 1,
    parameter int TRI_CAP = 512,
    parameter int EDGE_CAP = 256,
    parameter int ZW = 32,
    parameter int TIW = $clog2(TRI_CAP + 1),
    parameter int EIW = $clog2(EDGE_CAP + 1)
) (
    input  wire                   clk,
    input  wire                   rst,
    // list write ports (tile fetch)
    input  wire                   tri_we,
    input  wire [TIW-1:0]         tri_waddr,
    input  wire [ZW-1:0]          tri_wzmax,
    input  wire                   edge_we,
    input  wire [EIW-1:0]         edge_waddr,
    input  wire [ZW-1:0]          edge_wzmin,
    // one pass over the loaded lists
    input  wire                   start,
    input  wire [TIW-1:0]         n_tris,    // 1 .. TRI_CAP
    input  wire [EIW-1:0]         n_edges,   // 0 .. EDGE_CAP
    output wire                   busy,
    output reg                    done,      // one clock, after the pass's last issue
    // issue, one row a clock
    output reg  [LANES-1:0]       iss_valid,
    output reg  [TIW-1:0]         iss_tri,
    output reg  [LANES*EIW-1:0]   iss_edge,
    output reg                    tri_end,   // with the triangle's last row
    output reg                    tri_stop   // ... which ended on test 6
);
  localparam int ROWS = (EDGE_CAP + LANES - 1) / LANES;
  localparam int RW = $clog2(ROWS + 1);
  localparam int BAW = $clog2(ROWS) > 0 ? $clog2(ROWS) : 1;
  localparam int TAW = $clog2(TRI_CAP) > 0 ? $clog2(TRI_CAP) : 1;

  // ---- lists ---------------------------------------------------------------------------
  reg  [TIW-1:0] a_tri;
  reg  [RW-1:0]  a_row;
  wire [ZW-1:0]  tri_zmax;
  ListRam #(.DEPTH(TRI_CAP), .WIDTH(ZW)) tri_list (
      .clk(clk), .we(tri_we), .waddr(TAW'(tri_waddr)), .wdata(tri_wzmax), .raddr(TAW'(a_tri)), .rdata(tri_zmax));
  wire [LANES*ZW-1:0] row_zmin;
  genvar b;
  generate
    for (b = 0; b < LANES; b = b + 1) begin : bank
      wire mine = (32'(edge_waddr) % LANES) == b;
      ListRam #(.DEPTH(ROWS), .WIDTH(ZW)) edges (
          .clk(clk), .we(edge_we && mine), .waddr(BAW'(32'(edge_waddr) / LANES)), .wdata(edge_wzmin),
          .raddr(BAW'(a_row)), .rdata(row_zmin[b*ZW +: ZW]));
    end
  endgenerate

  // ---- stage A: row addresses ------------------------------------------------------------
  reg              a_valid, running;
  reg  [TIW-1:0]   p_tris;
  reg  [EIW-1:0]   p_edges;
  wire [RW-1:0]    rows = p_edges == 0 ? RW'(1) : RW'((32'(p_edges) + LANES - 1) / LANES);
  wire             a_last_row = a_row + 1 == rows;
  reg              b_valid;
  reg  [TIW-1:0]   b_tri;
  reg  [RW-1:0]    b_row;
  reg              b_last_row;
  // stage B's verdict on the row read last clock
  wire [LANES-1:0] b_behind, b_in_list;
  wire [LANES-1:0] b_issue;
  generate
    for (b = 0; b < LANES; b = b + 1) begin : cmp
      assign b_in_list[b] = 32'(b_row) * LANES + b < 32'(p_edges);
      assign b_behind[b] = b_in_list[b] && row_zmin[b*ZW +: ZW] > tri_zmax;  // z_max of b_tri, read with the row
    end
  endgenerate
  // a lane issues if it and every lane before it are in the list and not behind (edges sorted)
  wire [LANES-1:0] b_ok = b_in_list & ~b_behind;
  generate
    for (b = 0; b < LANES; b = b + 1) begin : iss
      assign b_issue[b] = b_valid && &b_ok[b:0];
    end
  endgenerate
  wire b_stop = b_valid && |b_behind;
  wire b_end = b_valid && (b_stop || b_last_row);
  // Stage A's row belongs to the triangle B just stopped: drop it and go on with the next triangle.
  wire squash = b_stop && !b_last_row;

  assign busy = running || a_valid || b_valid;

  always @(posedge clk) begin
    if (rst) begin
      running <= 1'b0;
      a_valid <= 1'b0;
      b_valid <= 1'b0;
      done <= 1'b0;
      iss_valid <= '0;
      tri_end <= 1'b0;
      tri_stop <= 1'b0;
    end else begin
      done <= 1'b0;
      // stage B -> issue registers
      iss_valid <= b_issue;
      iss_tri <= b_tri;
      tri_end <= b_end;
      tri_stop <= b_stop;
      for (int l = 0; l < LANES; l = l + 1) iss_edge[l*EIW +: EIW] <= EIW'(32'(b_row) * LANES + l);
      // stage A -> stage B
      b_valid <= a_valid && !squash;
      b_tri <= a_tri;
      b_row <= a_row;
      b_last_row <= a_last_row;
      if (start && !busy) begin
        running <= 1'b1;
        a_valid <= 1'b1;
        a_tri <= '0;
        a_row <= '0;
        p_tris <= n_tris;
        p_edges <= n_edges;
      end else if (running) begin
        if (squash) begin
          // A holds b_tri's next row: restart A at the triangle after it
          if (b_tri + 1 == p_tris) begin
            running <= 1'b0;
            a_valid <= 1'b0;
          end else begin
            a_tri <= b_tri + 1;
            a_row <= '0;
          end
        end else if (a_last_row) begin
          if (a_tri + 1 == p_tris) begin
            running <= 1'b0;
            a_valid <= 1'b0;
          end else begin
            a_tri <= a_tri + 1;
            a_row <= '0;
          end
        end else begin
          a_row <= a_row + 1;
        end
      end
      if (b_end && b_tri + 1 == p_tris) done <= 1'b1;  // the last triangle's last row
    end
  end

`ifndef SYNTHESIS
  always @(posedge clk) if (start && !busy && !rst) begin
    assert (n_tris >= 1 && 32'(n_tris) <= TRI_CAP) else $error("TileSequencer: n_tris outside 1..TRI_CAP");
    assert (32'(n_edges) <= EDGE_CAP) else $error("TileSequencer: n_edges beyond EDGE_CAP");
  end
  always @(posedge clk) if (!rst) begin
    assert (!(tri_we && 32'(tri_waddr) >= TRI_CAP)) else $error("TileSequencer: triangle write beyond TRI_CAP");
    assert (!(edge_we && 32'(edge_waddr) >= EDGE_CAP)) else $error("TileSequencer: edge write beyond EDGE_CAP");
  end
`endif
endmodule
