// PairReject: the early-visibility unit's culling tests of one silhouette edge against one
// triangle's polygon in the tile (SVGPU §3.2.1), on snapped integer coordinates, exact.
// LANES independent lanes (PairRejectLane), each takes one pair per clock; LATENCY = 3 clocks.
//
// Decision per pair (`out_code`), in the order model/visibility's analytic resolver applies
// the public tests (svgpu.h): the first that rejects names the code.
//   1 BEHIND   test 6: edge z_min > triangle z_max            (svgpu::edge_behind)
//   2 BOXES    test 2, boxes: the bounding boxes at most touch (svgpu::boxes_apart)
//   3 SHARED   test 4: the edge is one of the triangle's edges (svgpu::shares_edge)
//   4 ONE_SIDE test 1: the polygon lies on one side of the line (geom::classify != crosses)
//   5 MISSES   test 2: the segment misses the polygon's interior (geom::segment_overlaps)
//   0 DEPTH    survives tests 1, 2, 4, 6: test 3 (depth along the chord) decides
// A zero-length edge has no line (a = b = c = 0): every vertex is on it, so ONE_SIDE.
//
// Widths (model/geom/README.md, "Predicates and bit bounds"; g = 2^23):
//   snapped coordinate      |x|,|y| <= 2^23              CW = 25 (signed, tile corners included)
//   depth                   z < 2^ZW, ZW <= 32           unsigned
//   polygon line a, b / c   |a|,|b| <= 2^24 / |c| <= 2^47 LA = 26 / LC = 49 (signed)
//   implicit vertex x, y / w |x|,|y| <= 2^72 / 0 < w <= 2^49  PX = 74 / PW = 51 (signed)
//   side(line, vertex)      a x + b y + c w, < 2^98      100 bits (signed)
//   line eval at endpoint   a x + b y + c, < 2^49        51 bits (signed)
// The input bounds and the sums' bounds are asserted in simulation.
// The side of one polygon vertex to the edge's line, and the vertex's polygon line at the edge's
// endpoints a and b (stage 2 of a lane, MAXV of them). A module of its own so that synthesis
// maps it once (rtl_ref/synth, hierarchical flow).
module PairRejectVertex #(
    parameter int CW = 25, LA = 26, LC = 49, PX = 74, PW = 51, SW = 100, EW = 51
) (
    input  wire signed [LA-1:0] la, lb,    // the edge's line
    input  wire signed [LC-1:0] lc,
    input  wire signed [CW-1:0] ax, ay, bx, by,
    input  wire signed [LA-1:0] pa, pb,    // the polygon's line starting at the vertex
    input  wire signed [LC-1:0] pc,
    input  wire signed [PX-1:0] vx, vy,    // the vertex (x : y : w)
    input  wire signed [PW-1:0] vw,
    output wire signed [SW-1:0] side,
    output wire signed [EW-1:0] at_a, at_b
);
  assign side = SW'(la * vx) + SW'(lb * vy) + SW'(lc * vw);
  assign at_a = EW'(pa * ax) + EW'(pb * ay) + EW'(pc);
  assign at_b = EW'(pa * bx) + EW'(pb * by) + EW'(pc);
endmodule

// One lane: one pair per clock, latency 3.
module PairRejectLane #(
    parameter int MAXV = 8, ZW = 32, CW = 25, LA = 26, LC = 49, PX = 74, PW = 51, NW = 4
) (
    input  wire                  clk,
    input  wire                  rst,
    input  wire                  in_valid,
    input  wire signed [CW-1:0]  ax, ay, bx, by,
    input  wire [ZW-1:0]         az, bz,
    input  wire [3*CW-1:0]       t_x, t_y,
    input  wire [3*ZW-1:0]       t_z,
    input  wire [NW-1:0]         n,
    input  wire [MAXV*LA-1:0]    p_la, p_lb,
    input  wire [MAXV*LC-1:0]    p_lc,
    input  wire [MAXV*PX-1:0]    p_vx, p_vy,
    input  wire [MAXV*PW-1:0]    p_vw,
    output reg                   out_valid,
    output reg  [2:0]            out_code
);
  localparam int SW = 100;  // side of an implicit vertex
  localparam int EW = 51;   // a polygon line at a snapped point

  wire signed [CW-1:0] tx0 = t_x[0*CW +: CW], tx1 = t_x[1*CW +: CW], tx2 = t_x[2*CW +: CW];
  wire signed [CW-1:0] ty0 = t_y[0*CW +: CW], ty1 = t_y[1*CW +: CW], ty2 = t_y[2*CW +: CW];
  wire [ZW-1:0] tz0 = t_z[0*ZW +: ZW], tz1 = t_z[1*ZW +: ZW], tz2 = t_z[2*ZW +: ZW];

  // ---- stage 1: edge line, boxes, depth ranges, shared edge ------------------------
  // Line::through(a, b): a' = a.y - b.y, b' = b.x - a.x (|.| <= 2^24), c' = a.x b.y - a.y b.x (<= 2^47)
  wire signed [LA-1:0] la_w = LA'(ay) - LA'(by);
  wire signed [LA-1:0] lb_w = LA'(bx) - LA'(ax);
  wire signed [LC-1:0] lc_w = LC'(ax * by) - LC'(ay * bx);
  wire [ZW-1:0] ez_min = (az < bz) ? az : bz;
  wire [ZW-1:0] tz_max = (tz0 > tz1) ? ((tz0 > tz2) ? tz0 : tz2) : ((tz1 > tz2) ? tz1 : tz2);
  wire signed [CW-1:0] ex0 = (ax < bx) ? ax : bx, ex1 = (ax < bx) ? bx : ax;
  wire signed [CW-1:0] ey0 = (ay < by) ? ay : by, ey1 = (ay < by) ? by : ay;
  wire signed [CW-1:0] tbx0 = (tx0 < tx1) ? ((tx0 < tx2) ? tx0 : tx2) : ((tx1 < tx2) ? tx1 : tx2);
  wire signed [CW-1:0] tbx1 = (tx0 > tx1) ? ((tx0 > tx2) ? tx0 : tx2) : ((tx1 > tx2) ? tx1 : tx2);
  wire signed [CW-1:0] tby0 = (ty0 < ty1) ? ((ty0 < ty2) ? ty0 : ty2) : ((ty1 < ty2) ? ty1 : ty2);
  wire signed [CW-1:0] tby1 = (ty0 > ty1) ? ((ty0 > ty2) ? ty0 : ty2) : ((ty1 > ty2) ? ty1 : ty2);
  wire behind_w = ez_min > tz_max;
  wire boxes_w = (ex1 <= tbx0) || (ex0 >= tbx1) || (ey1 <= tby0) || (ey0 >= tby1);
  // vertices compare with depth (geom::Vertex ==)
  wire a_is0 = ax == tx0 && ay == ty0 && az == tz0, a_is1 = ax == tx1 && ay == ty1 && az == tz1,
       a_is2 = ax == tx2 && ay == ty2 && az == tz2;
  wire b_is0 = bx == tx0 && by == ty0 && bz == tz0, b_is1 = bx == tx1 && by == ty1 && bz == tz1,
       b_is2 = bx == tx2 && by == ty2 && bz == tz2;
  wire shared_w = (a_is0 && b_is1) || (a_is1 && b_is0) || (a_is1 && b_is2) || (a_is2 && b_is1) ||
                  (a_is2 && b_is0) || (a_is0 && b_is2);
  wire degenerate_w = ax == bx && ay == by;

  reg               s1_valid;
  reg [2:0]         s1_early;  // a reject code decided in stage 1, 0 if none
  reg signed [LA-1:0] s1_la, s1_lb;
  reg signed [LC-1:0] s1_lc;
  reg signed [CW-1:0] s1_ax, s1_ay, s1_bx, s1_by;
  reg [NW-1:0]      s1_n;
  reg [MAXV*LA-1:0] s1_pla, s1_plb;
  reg [MAXV*LC-1:0] s1_plc;
  reg [MAXV*PX-1:0] s1_pvx, s1_pvy;
  reg [MAXV*PW-1:0] s1_pvw;
  always @(posedge clk) begin
    if (rst) s1_valid <= 1'b0;
    else s1_valid <= in_valid;
    s1_early <= behind_w ? 3'd1 : boxes_w ? 3'd2 : shared_w ? 3'd3 : degenerate_w ? 3'd4 : 3'd0;
    s1_la <= la_w; s1_lb <= lb_w; s1_lc <= lc_w;
    s1_ax <= ax; s1_ay <= ay; s1_bx <= bx; s1_by <= by;
    s1_n <= n;
    s1_pla <= p_la; s1_plb <= p_lb;
    s1_plc <= p_lc;
    s1_pvx <= p_vx; s1_pvy <= p_vy;
    s1_pvw <= p_vw;
  end

  // ---- stage 2: side of every vertex (test 1), every polygon line at a and b (test 2) --
  wire [MAXV-1:0] pos_w, neg_w, apart_w;
  genvar v;
  generate
    for (v = 0; v < MAXV; v = v + 1) begin : vert
      wire signed [LA-1:0] pa = s1_pla[v*LA +: LA], pb = s1_plb[v*LA +: LA];
      wire signed [LC-1:0] pc = s1_plc[v*LC +: LC];
      wire signed [PX-1:0] vx = s1_pvx[v*PX +: PX], vy = s1_pvy[v*PX +: PX];
      wire signed [PW-1:0] vw = s1_pvw[v*PW +: PW];
      wire signed [SW-1:0] side;
      wire signed [EW-1:0] at_a, at_b;
      PairRejectVertex #(.CW(CW), .LA(LA), .LC(LC), .PX(PX), .PW(PW), .SW(SW), .EW(EW)) u (
          .la(s1_la), .lb(s1_lb), .lc(s1_lc), .ax(s1_ax), .ay(s1_ay), .bx(s1_bx), .by(s1_by),
          .pa(pa), .pb(pb), .pc(pc), .vx(vx), .vy(vy), .vw(vw), .side(side), .at_a(at_a), .at_b(at_b));
      wire used = v < s1_n;
      assign pos_w[v] = used && side > 0;
      assign neg_w[v] = used && side < 0;
      assign apart_w[v] = used && at_a <= 0 && at_b <= 0;
`ifndef SYNTHESIS
      always @(posedge clk) if (s1_valid && used) begin
        assert (vw > 0 && vw <= (PW'(1) << 49)) else $error("PairReject: vertex w out of (0, 2^49]");
        assert (vx >= -(PX'(1) << 72) && vx <= (PX'(1) << 72)) else $error("PairReject: vertex x beyond 2^72");
        assert (vy >= -(PX'(1) << 72) && vy <= (PX'(1) << 72)) else $error("PairReject: vertex y beyond 2^72");
        assert (pa >= -(LA'(1) << 24) && pa <= (LA'(1) << 24)) else $error("PairReject: line a beyond 2^24");
        assert (pb >= -(LA'(1) << 24) && pb <= (LA'(1) << 24)) else $error("PairReject: line b beyond 2^24");
        assert (pc >= -(LC'(1) << 47) && pc <= (LC'(1) << 47)) else $error("PairReject: line c beyond 2^47");
        assert (side > -(SW'(1) << 98) && side < (SW'(1) << 98)) else $error("PairReject: side beyond 2^98");
        assert (at_a > -(EW'(1) << 49) && at_a < (EW'(1) << 49)) else $error("PairReject: line eval beyond 2^49");
      end
`endif
    end
  endgenerate

  reg s2_valid;
  reg [2:0] s2_early;
  reg s2_crosses, s2_apart;
  always @(posedge clk) begin
    if (rst) s2_valid <= 1'b0;
    else s2_valid <= s1_valid;
    s2_early <= s1_early;
    s2_crosses <= |pos_w && |neg_w;
    s2_apart <= |apart_w;
  end

  // ---- stage 3: the decision -------------------------------------------------------
  always @(posedge clk) begin
    if (rst) out_valid <= 1'b0;
    else out_valid <= s2_valid;
    out_code <= s2_early != 3'd0 ? s2_early : !s2_crosses ? 3'd4 : s2_apart ? 3'd5 : 3'd0;
  end

`ifndef SYNTHESIS
  always @(posedge clk) if (in_valid && !rst) begin
    assert (ax >= -(CW'(1) << 23) && ax <= (CW'(1) << 23) && ay >= -(CW'(1) << 23) && ay <= (CW'(1) << 23))
      else $error("PairReject: edge endpoint a beyond 2^23");
    assert (bx >= -(CW'(1) << 23) && bx <= (CW'(1) << 23) && by >= -(CW'(1) << 23) && by <= (CW'(1) << 23))
      else $error("PairReject: edge endpoint b beyond 2^23");
    assert (32'(n) <= MAXV) else $error("PairReject: polygon has more than MAXV vertices");
  end
`endif
endmodule

// LANES PairRejectLanes side by side (ports flattened lane-major).
module PairReject #(
    parameter int LANES = 1,
    parameter int MAXV = 8,   // polygon vertices a lane holds (a triangle clipped to a tile: <= 7)
    parameter int ZW = 32,
    parameter int CW = 25,
    parameter int LA = 26,
    parameter int LC = 49,
    parameter int PX = 74,
    parameter int PW = 51,
    parameter int NW = 4      // width of the vertex count
) (
    input  wire                        clk,
    input  wire                        rst,
    input  wire [LANES-1:0]            in_valid,
    // the silhouette edge, endpoints a and b (x, y: CW signed; z: ZW unsigned)
    input  wire [LANES*CW-1:0]         e_ax, e_ay, e_bx, e_by,
    input  wire [LANES*ZW-1:0]         e_az, e_bz,
    // the triangle's three snapped vertices in setup order
    input  wire [LANES*3*CW-1:0]       t_x, t_y,
    input  wire [LANES*3*ZW-1:0]       t_z,
    // the triangle's polygon in the tile: n edges, edge i = line (a, b, c) and start vertex (x : y : w)
    input  wire [LANES*NW-1:0]         p_n,
    input  wire [LANES*MAXV*LA-1:0]    p_la, p_lb,
    input  wire [LANES*MAXV*LC-1:0]    p_lc,
    input  wire [LANES*MAXV*PX-1:0]    p_vx, p_vy,
    input  wire [LANES*MAXV*PW-1:0]    p_vw,
    output wire [LANES-1:0]            out_valid,
    output wire [LANES*3-1:0]          out_code
);
  genvar l;
  generate
    for (l = 0; l < LANES; l = l + 1) begin : lane
      PairRejectLane #(.MAXV(MAXV), .ZW(ZW), .CW(CW), .LA(LA), .LC(LC), .PX(PX), .PW(PW), .NW(NW)) u (
          .clk(clk), .rst(rst), .in_valid(in_valid[l]),
          .ax(e_ax[l*CW +: CW]), .ay(e_ay[l*CW +: CW]), .bx(e_bx[l*CW +: CW]), .by(e_by[l*CW +: CW]),
          .az(e_az[l*ZW +: ZW]), .bz(e_bz[l*ZW +: ZW]),
          .t_x(t_x[l*3*CW +: 3*CW]), .t_y(t_y[l*3*CW +: 3*CW]), .t_z(t_z[l*3*ZW +: 3*ZW]),
          .n(p_n[l*NW +: NW]),
          .p_la(p_la[l*MAXV*LA +: MAXV*LA]), .p_lb(p_lb[l*MAXV*LA +: MAXV*LA]), .p_lc(p_lc[l*MAXV*LC +: MAXV*LC]),
          .p_vx(p_vx[l*MAXV*PX +: MAXV*PX]), .p_vy(p_vy[l*MAXV*PX +: MAXV*PX]), .p_vw(p_vw[l*MAXV*PW +: MAXV*PW]),
          .out_valid(out_valid[l]), .out_code(out_code[l*3 +: 3]));
    end
  endgenerate
endmodule
