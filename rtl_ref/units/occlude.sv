// Occlude: SVGPU §3.3 for one piece of triangle t against a stream of original opaque
// triangles u (svgpu::occludes at geom::interior_point). LANES independent lanes. A lane
// takes a piece (its vertices 0, 1, 2 and t's depth plane, p_valid) and computes its interior
// point q, the centroid (x0 w1 w2 + x1 w0 w2 + x2 w0 w1 : ... : 3 w0 w1 w2) (geom::centroid),
// and t's depth numerator at q in 2 clocks; then one occluder a clock (o_valid): u contains q
// under the tie rule and is nearer there, or level with it and submitted earlier (smaller id);
// the verdict comes 2 clocks after the occluder. Every sign is exact (no filter: hardware
// evaluates the exact integers the C++ falls back to).
//
// Widths (model/geom/README.md, D = ZW <= 32): implicit vertex |x|,|y| <= 2^72 (PX = 74),
// 0 < w <= 2^49 (PW = 51); q: |x|,|y| < 2^172 (QX = 174), 0 < w < 2^149 (QW = 151); edge
// lines |a|,|b| <= 2^24 (LA = 26), |c| <= 2^47 (LC = 49); side at q < 2^198 (200 bits);
// plane alpha, beta <= 2^(25+D) (AW = 59), gamma < 2^(50+D) (GW = 84), 0 < area <= 2^49
// (PW = 51); M = alpha x + beta y + gamma w < 2^(200+D) (MW = 234); M_u area_t - M_t area_u
// < 2^(250+D) (284 bits). Asserted in simulation.
// A lane's arithmetic blocks are modules of their own so that synthesis maps each once
// (rtl_ref/synth, hierarchical flow).

// A coordinate of the centroid's numerator: x0 w1 w2 + x1 w0 w2 + x2 w0 w1 (two per lane: x, y).
module OccludeCentroidNum #(
    parameter int PX = 74, PW = 51, QX = 174
) (
    input  wire signed [PX-1:0]   x0, x1, x2,
    input  wire signed [2*PW-1:0] w12, w02, w01,
    output wire signed [QX-1:0]   c
);
  assign c = QX'(x0 * w12) + QX'(x1 * w02) + QX'(x2 * w01);
endmodule

// A plane's depth numerator at q: M = alpha x + beta y + gamma w (two per lane: t's and u's).
module OccludeNumerator #(
    parameter int QX = 174, QW = 151, AW = 59, GW = 84, MW = 234
) (
    input  wire signed [AW-1:0] alpha, beta,
    input  wire signed [GW-1:0] gamma,
    input  wire signed [QX-1:0] x, y,
    input  wire signed [QW-1:0] w,
    output wire signed [MW-1:0] m
);
  assign m = MW'(alpha * x) + MW'(beta * y) + MW'(gamma * w);
endmodule

// The side of q to an occluder's edge line: a x + b y + c w (three per lane).
module OccludeEdgeSide #(
    parameter int QX = 174, QW = 151, LA = 26, LC = 49, SW = 200
) (
    input  wire signed [LA-1:0] a, b,
    input  wire signed [LC-1:0] c,
    input  wire signed [QX-1:0] x, y,
    input  wire signed [QW-1:0] w,
    output wire signed [SW-1:0] s
);
  assign s = SW'(a * x) + SW'(b * y) + SW'(c * w);
endmodule

module OccludeLane #(
    parameter int PX = 74, PW = 51, QX = 174, QW = 151, LA = 26, LC = 49, AW = 59, GW = 84, MW = 234,
    parameter int IDW = 32
) (
    input  wire                  clk,
    input  wire                  rst,
    // the piece: vertices 0, 1, 2 and its triangle's plane and id
    input  wire                  p_valid,
    input  wire [3*PX-1:0]       p_vx, p_vy,
    input  wire [3*PW-1:0]       p_vw,
    input  wire signed [AW-1:0]  t_alpha, t_beta,
    input  wire signed [GW-1:0]  t_gamma,
    input  wire signed [PW-1:0]  t_area,
    input  wire [IDW-1:0]        t_id,
    output reg                   q_ready,   // q and t's numerator are held (2 clocks after p_valid)
    output reg signed [QX-1:0]   q_x, q_y,
    output reg signed [QW-1:0]   q_w,
    // an occluder: its three edge lines (interior positive), whether it has area, plane, id
    input  wire                  o_valid,
    input  wire [3*LA-1:0]       u_la, u_lb,
    input  wire [3*LC-1:0]       u_lc,
    input  wire                  u_edges_valid,
    input  wire signed [AW-1:0]  u_alpha, u_beta,
    input  wire signed [GW-1:0]  u_gamma,
    input  wire signed [PW-1:0]  u_area,
    input  wire [IDW-1:0]        u_id,
    output reg                   r_valid,
    output reg                   r_occluded
);
  localparam int SW = 200, XW = 284;

  // ---- piece stage 1: the centroid -----------------------------------------------------
  wire signed [PX-1:0] x0 = p_vx[0 +: PX], x1 = p_vx[PX +: PX], x2 = p_vx[2*PX +: PX];
  wire signed [PX-1:0] y0 = p_vy[0 +: PX], y1 = p_vy[PX +: PX], y2 = p_vy[2*PX +: PX];
  wire signed [PW-1:0] w0 = p_vw[0 +: PW], w1 = p_vw[PW +: PW], w2 = p_vw[2*PW +: PW];
  wire signed [2*PW-1:0] w12 = w1 * w2, w02 = w0 * w2, w01 = w0 * w1;
  wire signed [QX-1:0] cx, cy;
  OccludeCentroidNum #(.PX(PX), .PW(PW), .QX(QX)) cx_num (
      .x0(x0), .x1(x1), .x2(x2), .w12(w12), .w02(w02), .w01(w01), .c(cx));
  OccludeCentroidNum #(.PX(PX), .PW(PW), .QX(QX)) cy_num (
      .x0(y0), .x1(y1), .x2(y2), .w12(w12), .w02(w02), .w01(w01), .c(cy));
  wire signed [QW-1:0] cw = QW'(QW'(3) * w0 * w12);
  reg p1;
  reg signed [AW-1:0] ta, tb;
  reg signed [GW-1:0] tg;
  reg signed [PW-1:0] tarea;
  reg [IDW-1:0] tid;
  // ---- piece stage 2: t's numerator at q -------------------------------------------------
  wire signed [MW-1:0] mt;
  OccludeNumerator #(.QX(QX), .QW(QW), .AW(AW), .GW(GW), .MW(MW)) mt_num (
      .alpha(ta), .beta(tb), .gamma(tg), .x(q_x), .y(q_y), .w(q_w), .m(mt));
  reg signed [MW-1:0] m_t;
  always @(posedge clk) begin
    if (rst) begin
      p1 <= 1'b0;
      q_ready <= 1'b0;
    end else begin
      p1 <= p_valid;
      if (p_valid) q_ready <= 1'b0;
      else if (p1) q_ready <= 1'b1;
    end
    if (p_valid) begin
      q_x <= cx; q_y <= cy; q_w <= cw;
      ta <= t_alpha; tb <= t_beta; tg <= t_gamma; tarea <= t_area; tid <= t_id;
    end
    if (p1) m_t <= mt;
  end

  // ---- occluder stage 1: sides of q, u's numerator at q ----------------------------------
  wire [2:0] in_edge;
  genvar k;
  generate
    for (k = 0; k < 3; k = k + 1) begin : edge_side
      wire signed [LA-1:0] a = u_la[k*LA +: LA], b = u_lb[k*LA +: LA];
      wire signed [LC-1:0] c = u_lc[k*LC +: LC];
      wire signed [SW-1:0] s;
      OccludeEdgeSide #(.QX(QX), .QW(QW), .LA(LA), .LC(LC), .SW(SW)) u (.a(a), .b(b), .c(c), .x(q_x), .y(q_y), .w(q_w), .s(s));
      // tie rule: on the line counts as in_edge iff (a, b) is lexicographically positive
      assign in_edge[k] = s > 0 || (s == 0 && (a > 0 || (a == 0 && b > 0)));
`ifndef SYNTHESIS
      always @(posedge clk) if (o_valid && !rst) begin
        assert (s > -(SW'(1) << 198) && s < (SW'(1) << 198)) else $error("Occlude: side beyond 2^198");
        assert (a >= -(LA'(1) << 24) && a <= (LA'(1) << 24) && b >= -(LA'(1) << 24) && b <= (LA'(1) << 24))
          else $error("Occlude: edge a, b beyond 2^24");
        assert (c >= -(LC'(1) << 47) && c <= (LC'(1) << 47)) else $error("Occlude: edge c beyond 2^47");
      end
`endif
    end
  endgenerate
  wire signed [MW-1:0] mu;
  OccludeNumerator #(.QX(QX), .QW(QW), .AW(AW), .GW(GW), .MW(MW)) mu_num (
      .alpha(u_alpha), .beta(u_beta), .gamma(u_gamma), .x(q_x), .y(q_y), .w(q_w), .m(mu));
  reg o1, o1_contains, o1_earlier;
  reg signed [MW-1:0] m_u;
  reg signed [PW-1:0] uarea;
  always @(posedge clk) begin
    if (rst) o1 <= 1'b0;
    else o1 <= o_valid;
    o1_contains <= u_edges_valid && &in_edge;
    o1_earlier <= u_id < tid;
    m_u <= mu;
    uarea <= u_area;
  end
  // ---- occluder stage 2: sign(z_u - z_t) = sign(M_u area_t - M_t area_u) -----------------
  wire signed [XW-1:0] d = XW'(m_u * tarea) - XW'(m_t * uarea);
  always @(posedge clk) begin
    if (rst) r_valid <= 1'b0;
    else r_valid <= o1;
    r_occluded <= o1_contains && (d < 0 || (d == 0 && o1_earlier));
  end

`ifndef SYNTHESIS
  always @(posedge clk) if (!rst) begin
    if (p_valid) begin
      assert (w0 > 0 && w1 > 0 && w2 > 0 && w0 <= (PW'(1) << 49) && w1 <= (PW'(1) << 49) && w2 <= (PW'(1) << 49))
        else $error("Occlude: vertex w out of (0, 2^49]");
      assert (t_area > 0 && t_area <= (PW'(1) << 49)) else $error("Occlude: t area out of (0, 2^49]");
      assert (cx > -(QX'(1) << 172) && cx < (QX'(1) << 172) && cy > -(QX'(1) << 172) && cy < (QX'(1) << 172))
        else $error("Occlude: centroid x, y beyond 2^172");
      assert (cw > 0 && cw < (QW'(1) << 149)) else $error("Occlude: centroid w out of (0, 2^149)");
    end
    if (o_valid) begin
      assert (!u_edges_valid || (u_area > 0 && u_area <= (PW'(1) << 49))) else $error("Occlude: u area out of (0, 2^49]");
      assert (mu > -(MW'(1) << 232) && mu < (MW'(1) << 232)) else $error("Occlude: M_u beyond 2^232");
    end
    if (o1) assert (d > -(XW'(1) << 282) && d < (XW'(1) << 282)) else $error("Occlude: depth difference beyond 2^282");
    if (p1) assert (mt > -(MW'(1) << 232) && mt < (MW'(1) << 232)) else $error("Occlude: M_t beyond 2^232");
  end
`endif
endmodule

// LANES OccludeLanes side by side (ports flattened lane-major).
module Occlude #(
    parameter int LANES = 1,
    parameter int PX = 74, PW = 51, QX = 174, QW = 151, LA = 26, LC = 49, AW = 59, GW = 84, MW = 234,
    parameter int IDW = 32
) (
    input  wire                   clk,
    input  wire                   rst,
    input  wire [LANES-1:0]       p_valid,
    input  wire [LANES*3*PX-1:0]  p_vx, p_vy,
    input  wire [LANES*3*PW-1:0]  p_vw,
    input  wire [LANES*AW-1:0]    t_alpha, t_beta,
    input  wire [LANES*GW-1:0]    t_gamma,
    input  wire [LANES*PW-1:0]    t_area,
    input  wire [LANES*IDW-1:0]   t_id,
    output wire [LANES-1:0]       q_ready,
    output wire [LANES*QX-1:0]    q_x, q_y,
    output wire [LANES*QW-1:0]    q_w,
    input  wire [LANES-1:0]       o_valid,
    input  wire [LANES*3*LA-1:0]  u_la, u_lb,
    input  wire [LANES*3*LC-1:0]  u_lc,
    input  wire [LANES-1:0]       u_edges_valid,
    input  wire [LANES*AW-1:0]    u_alpha, u_beta,
    input  wire [LANES*GW-1:0]    u_gamma,
    input  wire [LANES*PW-1:0]    u_area,
    input  wire [LANES*IDW-1:0]   u_id,
    output wire [LANES-1:0]       r_valid,
    output wire [LANES-1:0]       r_occluded
);
  genvar l;
  generate
    for (l = 0; l < LANES; l = l + 1) begin : lane
      OccludeLane #(.PX(PX), .PW(PW), .QX(QX), .QW(QW), .LA(LA), .LC(LC), .AW(AW), .GW(GW), .MW(MW), .IDW(IDW)) u (
          .clk(clk), .rst(rst), .p_valid(p_valid[l]), .p_vx(p_vx[l*3*PX +: 3*PX]), .p_vy(p_vy[l*3*PX +: 3*PX]),
          .p_vw(p_vw[l*3*PW +: 3*PW]), .t_alpha(t_alpha[l*AW +: AW]), .t_beta(t_beta[l*AW +: AW]),
          .t_gamma(t_gamma[l*GW +: GW]), .t_area(t_area[l*PW +: PW]), .t_id(t_id[l*IDW +: IDW]),
          .q_ready(q_ready[l]), .q_x(q_x[l*QX +: QX]), .q_y(q_y[l*QX +: QX]), .q_w(q_w[l*QW +: QW]),
          .o_valid(o_valid[l]), .u_la(u_la[l*3*LA +: 3*LA]), .u_lb(u_lb[l*3*LA +: 3*LA]), .u_lc(u_lc[l*3*LC +: 3*LC]),
          .u_edges_valid(u_edges_valid[l]), .u_alpha(u_alpha[l*AW +: AW]), .u_beta(u_beta[l*AW +: AW]),
          .u_gamma(u_gamma[l*GW +: GW]), .u_area(u_area[l*PW +: PW]), .u_id(u_id[l*IDW +: IDW]),
          .r_valid(r_valid[l]), .r_occluded(r_occluded[l]));
    end
  endgenerate
endmodule
