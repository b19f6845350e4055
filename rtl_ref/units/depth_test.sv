// DepthTest: SVGPU §3.2.1 test 3 of a pair that passed tests 1, 2, 4 and 6 (PairReject code 0):
// over the part of the silhouette edge inside the triangle's polygon, is the edge nearer than
// the triangle's plane somewhere (or level with it at both ends)? The verdict of
// svgpu::survives for such a pair. LANES independent lanes, one pair per clock per lane,
// latency 3:
//   1. the sides of the polygon's vertices to the edge's line;
//   2. the chord's ends (geom::chord): where the line leaves the positive block, `first`, and
//      where it enters it, `second`: a vertex on the line, or the crossing of its edge line
//      with the edge's line (geom::intersect; the verdict depends only on the point);
//   3. at each end, sign(z_t - z_edge): at the edge's own endpoint when the end lies beyond
//      it (geom::depth_order at a snapped point), else the depth along the edge
//      (geom::depth_order_edge, exact: sign(M den - E area w));
//   then: first > 0, or second > 0, or both level.
//
// Widths (model/geom/README.md, D = ZW <= 32): coordinates CW = 25; lines LA = 26 / LC = 49;
// implicit points x, y PX = 74 / w PW = 51; side 100 bits; plane alpha, beta AW = 59,
// gamma GW = 84, area PW = 51; along the edge < 2^98 (100 bits); depth at an endpoint
// < 2^(51+D) + 2^(49+D) (86 bits); t = num / den: |num|, |den| <= 2^73 (75 bits); E <= 2^(74+D)
// (108 bits); M < 2^(100+D) (134 bits); M den - E area w < 2^(174+D) (208 bits). Asserted in
// simulation.
// A lane's arithmetic blocks are modules of their own so that synthesis maps each once
// (rtl_ref/synth, hierarchical flow).

// The side of a polygon vertex (x : y : w) to the edge's line (a, b, c): a x + b y + c w
// (stage 1, MAXV per lane).
module DepthTestSide #(
    parameter int LA = 26, LC = 49, PX = 74, PW = 51, SW = 100
) (
    input  wire signed [LA-1:0] la, lb,
    input  wire signed [LC-1:0] lc,
    input  wire signed [PX-1:0] x, y,
    input  wire signed [PW-1:0] w,
    output wire signed [SW-1:0] s
);
  assign s = SW'(la * x) + SW'(lb * y) + SW'(lc * w);
endmodule

// The crossing of a polygon edge's line (pa, pb, pc) with the edge's line (la, lb, lc), the point
// of l x l_i normalised to w > 0 (stage 2, one per chord end).
module DepthTestCrossing #(
    parameter int LA = 26, LC = 49, PX = 74, PW = 51
) (
    input  wire signed [LA-1:0] la, lb, pa, pb,
    input  wire signed [LC-1:0] lc, pc,
    output wire signed [PX-1:0] x, y,
    output wire signed [PW-1:0] w
);
  wire signed [PX-1:0] x_i = PX'(lb * pc) - PX'(pb * lc), y_i = PX'(lc * pa) - PX'(pc * la);
  wire signed [PW-1:0] w_i = PW'(la * pb) - PW'(pa * lb);
  assign x = w_i < 0 ? -x_i : x_i;
  assign y = w_i < 0 ? -y_i : y_i;
  assign w = w_i < 0 ? -w_i : w_i;
endmodule

// The depth along the edge at a chord end (x : y : w) against the triangle's plane, exact:
// M den - E area w (stage 3, one per chord end; its sign is geom::depth_order_edge's).
module DepthTestAlongEdge #(
    parameter int ZW = 32, CW = 25, PX = 74, PW = 51, AW = 59, GW = 84,
    parameter int NUMW = 75, EW = 108, MW = 134, DW = 208
) (
    input  wire signed [PX-1:0] x, y,
    input  wire signed [PW-1:0] w,
    input  wire signed [CW-1:0] ax, ay,
    input  wire [ZW-1:0]        az,
    input  wire signed [CW:0]   dx, dy,
    input  wire signed [ZW+1:0] dz,
    input  wire                 x_major,
    input  wire signed [AW-1:0] alpha, beta,
    input  wire signed [GW-1:0] gamma,
    input  wire signed [PW-1:0] area,
    output wire signed [DW-1:0] de
);
  wire signed [NUMW-1:0] num0 = x_major ? NUMW'(x) - NUMW'(ax * w) : NUMW'(y) - NUMW'(ay * w);
  wire signed [NUMW-1:0] den0 = x_major ? NUMW'(dx * w) : NUMW'(dy * w);
  wire signed [NUMW-1:0] num = den0 < 0 ? -num0 : num0, den = den0 < 0 ? -den0 : den0;
  wire signed [EW-1:0] e = EW'($signed({1'b0, az}) * den) + EW'(dz * num);
  wire signed [MW-1:0] m = MW'(alpha * x) + MW'(beta * y) + MW'(gamma * w);
  wire signed [2*PW-1:0] aw = area * w;
  assign de = DW'(m * den) - DW'(e * aw);
endmodule

module DepthTestLane #(
    parameter int MAXV = 8,
    parameter int ZW = 32, CW = 25, LA = 26, LC = 49, PX = 74, PW = 51, AW = 59, GW = 84, NW = 4
) (
    input  wire                 clk,
    input  wire                 rst,
    input  wire                 in_valid,
    input  wire signed [CW-1:0] ax, ay, bx, by,
    input  wire [ZW-1:0]        az, bz,
    input  wire [NW-1:0]        n,
    input  wire [MAXV*LA-1:0]   p_la, p_lb,
    input  wire [MAXV*LC-1:0]   p_lc,
    input  wire [MAXV*PX-1:0]   p_vx, p_vy,
    input  wire [MAXV*PW-1:0]   p_vw,
    input  wire signed [AW-1:0] alpha, beta,
    input  wire signed [GW-1:0] gamma,
    input  wire signed [PW-1:0] area,
    output reg                  out_valid,
    output reg                  out_survives
);
  localparam int SW = 100, NUMW = 75, EW = 108, MW = 134, DW = 208, ZPW = 86;

  // ---- stage 1: the edge's line, the vertices' sides ----------------------------------
  wire signed [LA-1:0] la = LA'(ay) - LA'(by);
  wire signed [LA-1:0] lb = LA'(bx) - LA'(ax);
  wire signed [LC-1:0] lc = LC'(ax * by) - LC'(ay * bx);
  wire [MAXV-1:0] pos_w, zero_w;
  genvar v;
  generate
    for (v = 0; v < MAXV; v = v + 1) begin : side
      wire signed [PX-1:0] x = p_vx[v*PX +: PX], y = p_vy[v*PX +: PX];
      wire signed [PW-1:0] w = p_vw[v*PW +: PW];
      wire signed [SW-1:0] s;
      DepthTestSide #(.LA(LA), .LC(LC), .PX(PX), .PW(PW), .SW(SW)) u (.la(la), .lb(lb), .lc(lc), .x(x), .y(y), .w(w), .s(s));
      assign pos_w[v] = s > 0;
      assign zero_w[v] = s == 0;
    end
  endgenerate
  reg s1_valid;
  reg signed [CW-1:0] s1_ax, s1_ay, s1_bx, s1_by;
  reg [ZW-1:0] s1_az, s1_bz;
  reg signed [LA-1:0] s1_la, s1_lb;
  reg signed [LC-1:0] s1_lc;
  reg [NW-1:0] s1_n;
  reg [MAXV-1:0] s1_pos, s1_zero;
  reg [MAXV*LA-1:0] s1_pla, s1_plb;
  reg [MAXV*LC-1:0] s1_plc;
  reg [MAXV*PX-1:0] s1_pvx, s1_pvy;
  reg [MAXV*PW-1:0] s1_pvw;
  reg signed [AW-1:0] s1_alpha, s1_beta;
  reg signed [GW-1:0] s1_gamma;
  reg signed [PW-1:0] s1_area;
  always @(posedge clk) begin
    if (rst) s1_valid <= 1'b0;
    else s1_valid <= in_valid;
    s1_ax <= ax; s1_ay <= ay; s1_bx <= bx; s1_by <= by; s1_az <= az; s1_bz <= bz;
    s1_la <= la; s1_lb <= lb; s1_lc <= lc; s1_n <= n; s1_pos <= pos_w; s1_zero <= zero_w;
    s1_pla <= p_la; s1_plb <= p_lb; s1_plc <= p_lc; s1_pvx <= p_vx; s1_pvy <= p_vy; s1_pvw <= p_vw;
    s1_alpha <= alpha; s1_beta <= beta; s1_gamma <= gamma; s1_area <= area;
  end

  // ---- stage 2: the chord's ends --------------------------------------------------------
  // Edge i runs from vertex i to vertex next(i). first: pos(i) && !pos(next); second: !pos(i) && pos(next).
  localparam int IW = $clog2(MAXV) > 0 ? $clog2(MAXV) : 1;
  wire [MAXV*LA-1:0] fla_all, flb_all, gla_all, glb_all;
  wire [MAXV*LC-1:0] flc_all, glc_all;
  wire [MAXV*PX-1:0] fvx_all, fvy_all, gvx_all, gvy_all;
  wire [MAXV*PW-1:0] fvw_all, gvw_all;
  wire [MAXV-1:0] fon_all, gon_all;
  generate
    for (v = 0; v < MAXV; v = v + 1) begin : chord
      wire [IW-1:0] nx = (32'(v) + 1 == 32'(s1_n)) ? '0 : IW'(v + 1);
      wire used = 32'(v) < 32'(s1_n);
      wire sel_f = used && s1_pos[v] && !s1_pos[nx];  // edge v leaves the positive block
      wire sel_g = used && !s1_pos[v] && s1_pos[nx];  // edge v enters it
      assign fla_all[v*LA +: LA] = sel_f ? s1_pla[v*LA +: LA] : '0;
      assign flb_all[v*LA +: LA] = sel_f ? s1_plb[v*LA +: LA] : '0;
      assign flc_all[v*LC +: LC] = sel_f ? s1_plc[v*LC +: LC] : '0;
      assign fvx_all[v*PX +: PX] = sel_f ? s1_pvx[nx*PX +: PX] : '0;
      assign fvy_all[v*PX +: PX] = sel_f ? s1_pvy[nx*PX +: PX] : '0;
      assign fvw_all[v*PW +: PW] = sel_f ? s1_pvw[nx*PW +: PW] : '0;
      assign fon_all[v] = sel_f && s1_zero[nx];
      assign gla_all[v*LA +: LA] = sel_g ? s1_pla[v*LA +: LA] : '0;
      assign glb_all[v*LA +: LA] = sel_g ? s1_plb[v*LA +: LA] : '0;
      assign glc_all[v*LC +: LC] = sel_g ? s1_plc[v*LC +: LC] : '0;
      assign gvx_all[v*PX +: PX] = sel_g ? s1_pvx[v*PX +: PX] : '0;
      assign gvy_all[v*PX +: PX] = sel_g ? s1_pvy[v*PX +: PX] : '0;
      assign gvw_all[v*PW +: PW] = sel_g ? s1_pvw[v*PW +: PW] : '0;
      assign gon_all[v] = sel_g && s1_zero[v];
    end
  endgenerate
  // one edge of a strictly convex polygon leaves the positive block, one enters it: OR selects it
  reg signed [LA-1:0] f_la, f_lb, g_la, g_lb;
  reg signed [LC-1:0] f_lc, g_lc;
  reg signed [PX-1:0] f_vx, f_vy, g_vx, g_vy;
  reg signed [PW-1:0] f_vw, g_vw;
  wire f_on = |fon_all, g_on = |gon_all;
  always @(*) begin
    f_la = '0; f_lb = '0; f_lc = '0; f_vx = '0; f_vy = '0; f_vw = '0;
    g_la = '0; g_lb = '0; g_lc = '0; g_vx = '0; g_vy = '0; g_vw = '0;
    for (int i = 0; i < MAXV; i = i + 1) begin
      f_la = f_la | fla_all[i*LA +: LA]; f_lb = f_lb | flb_all[i*LA +: LA]; f_lc = f_lc | flc_all[i*LC +: LC];
      f_vx = f_vx | fvx_all[i*PX +: PX]; f_vy = f_vy | fvy_all[i*PX +: PX]; f_vw = f_vw | fvw_all[i*PW +: PW];
      g_la = g_la | gla_all[i*LA +: LA]; g_lb = g_lb | glb_all[i*LA +: LA]; g_lc = g_lc | glc_all[i*LC +: LC];
      g_vx = g_vx | gvx_all[i*PX +: PX]; g_vy = g_vy | gvy_all[i*PX +: PX]; g_vw = g_vw | gvw_all[i*PW +: PW];
    end
  end
  // crossing of a polygon edge line with the edge's line, w > 0 (the point of l x l_i)
  wire signed [PX-1:0] fx_n, fy_n, gx_n, gy_n;
  wire signed [PW-1:0] fw_n, gw_n;
  DepthTestCrossing #(.LA(LA), .LC(LC), .PX(PX), .PW(PW)) f_cross (
      .la(s1_la), .lb(s1_lb), .lc(s1_lc), .pa(f_la), .pb(f_lb), .pc(f_lc), .x(fx_n), .y(fy_n), .w(fw_n));
  DepthTestCrossing #(.LA(LA), .LC(LC), .PX(PX), .PW(PW)) g_cross (
      .la(s1_la), .lb(s1_lb), .lc(s1_lc), .pa(g_la), .pb(g_lb), .pc(g_lc), .x(gx_n), .y(gy_n), .w(gw_n));
  reg s2_valid;
  reg signed [PX-1:0] s2_fx, s2_fy, s2_gx, s2_gy;
  reg signed [PW-1:0] s2_fw, s2_gw;
  reg signed [CW-1:0] s2_ax, s2_ay, s2_bx, s2_by;
  reg [ZW-1:0] s2_az, s2_bz;
  reg signed [AW-1:0] s2_alpha, s2_beta;
  reg signed [GW-1:0] s2_gamma;
  reg signed [PW-1:0] s2_area;
  always @(posedge clk) begin
    if (rst) s2_valid <= 1'b0;
    else s2_valid <= s1_valid;
    s2_fx <= f_on ? f_vx : fx_n;
    s2_fy <= f_on ? f_vy : fy_n;
    s2_fw <= f_on ? f_vw : fw_n;
    s2_gx <= g_on ? g_vx : gx_n;
    s2_gy <= g_on ? g_vy : gy_n;
    s2_gw <= g_on ? g_vw : gw_n;
    s2_ax <= s1_ax; s2_ay <= s1_ay; s2_bx <= s1_bx; s2_by <= s1_by; s2_az <= s1_az; s2_bz <= s1_bz;
    s2_alpha <= s1_alpha; s2_beta <= s1_beta; s2_gamma <= s1_gamma; s2_area <= s1_area;
  end

  // ---- stage 3: sign(z_t - z_edge) at both ends -----------------------------------------
  wire signed [CW:0] dx = (CW+1)'(s2_bx) - (CW+1)'(s2_ax), dy = (CW+1)'(s2_by) - (CW+1)'(s2_ay);
  wire x_major = (dx < 0 ? -dx : dx) >= (dy < 0 ? -dy : dy);
  wire signed [ZW+1:0] dz = (ZW+2)'(s2_bz) - (ZW+2)'(s2_az);

  // along: sign((c - p) . d) for the end c and the edge endpoint p
  wire signed [NUMW-1:0] fdx = NUMW'(s2_fx) - NUMW'(s2_ax * s2_fw), fdy = NUMW'(s2_fy) - NUMW'(s2_ay * s2_fw);
  wire signed [NUMW-1:0] gdx = NUMW'(s2_gx) - NUMW'(s2_bx * s2_gw), gdy = NUMW'(s2_gy) - NUMW'(s2_by * s2_gw);
  wire signed [SW-1:0] along_f = SW'(fdx * dx) + SW'(fdy * dy);
  wire signed [SW-1:0] along_g = SW'(gdx * dx) + SW'(gdy * dy);
  // depth at the edge's endpoints: alpha x + beta y + gamma - z area
  wire signed [ZPW-1:0] zp_a = ZPW'(s2_alpha * s2_ax) + ZPW'(s2_beta * s2_ay) + ZPW'(s2_gamma) - ZPW'($signed({1'b0, s2_az}) * s2_area);
  wire signed [ZPW-1:0] zp_b = ZPW'(s2_alpha * s2_bx) + ZPW'(s2_beta * s2_by) + ZPW'(s2_gamma) - ZPW'($signed({1'b0, s2_bz}) * s2_area);
  // depth along the edge at each end (x, y : w): end 0 = first, end 1 = second
  wire signed [DW-1:0] de [0:1];
  genvar k;
  generate
    for (k = 0; k < 2; k = k + 1) begin : along_edge
      wire signed [PX-1:0] x = k == 0 ? s2_fx : s2_gx, y = k == 0 ? s2_fy : s2_gy;
      wire signed [PW-1:0] w = k == 0 ? s2_fw : s2_gw;
      DepthTestAlongEdge #(.ZW(ZW), .CW(CW), .PX(PX), .PW(PW), .AW(AW), .GW(GW), .NUMW(NUMW), .EW(EW), .MW(MW), .DW(DW)) u (
          .x(x), .y(y), .w(w), .ax(s2_ax), .ay(s2_ay), .az(s2_az), .dx(dx), .dy(dy), .dz(dz), .x_major(x_major),
          .alpha(s2_alpha), .beta(s2_beta), .gamma(s2_gamma), .area(s2_area), .de(de[k]));
    end
  endgenerate
  wire signed [DW-1:0] de_f = de[0], de_g = de[1];
  wire use_a = along_f < 0, use_b = along_g > 0;
  wire f_pos = use_a ? zp_a > 0 : de_f > 0, f_zero = use_a ? zp_a == 0 : de_f == 0;
  wire g_pos = use_b ? zp_b > 0 : de_g > 0, g_zero = use_b ? zp_b == 0 : de_g == 0;
  always @(posedge clk) begin
    if (rst) out_valid <= 1'b0;
    else out_valid <= s2_valid;
    out_survives <= f_pos || g_pos || (f_zero && g_zero);
  end

`ifndef SYNTHESIS
  always @(posedge clk) if (s2_valid && !rst) begin
    assert (s2_fw > 0 && s2_fw <= (PW'(1) << 49) && s2_gw > 0 && s2_gw <= (PW'(1) << 49))
      else $error("DepthTest: chord end w out of (0, 2^49]");
    assert (along_f > -(SW'(1) << 98) && along_f < (SW'(1) << 98) && along_g > -(SW'(1) << 98) && along_g < (SW'(1) << 98))
      else $error("DepthTest: along beyond 2^98");
    assert (de_f > -(DW'(1) << 206) && de_f < (DW'(1) << 206) && de_g > -(DW'(1) << 206) && de_g < (DW'(1) << 206))
      else $error("DepthTest: depth along the edge beyond 2^206");
    assert (zp_a > -(ZPW'(1) << 84) && zp_a < (ZPW'(1) << 84) && zp_b > -(ZPW'(1) << 84) && zp_b < (ZPW'(1) << 84))
      else $error("DepthTest: depth at an endpoint beyond 2^84");
  end
  always @(posedge clk) if (in_valid && !rst) begin
    assert (32'(n) <= MAXV && n >= 3) else $error("DepthTest: polygon outside 3..MAXV vertices");
    assert (area > 0 && area <= (PW'(1) << 49)) else $error("DepthTest: area out of (0, 2^49]");
  end
`endif
endmodule

// LANES DepthTestLanes side by side (ports flattened lane-major).
module DepthTest #(
    parameter int LANES = 1, MAXV = 8,
    parameter int ZW = 32, CW = 25, LA = 26, LC = 49, PX = 74, PW = 51, AW = 59, GW = 84, NW = 4
) (
    input  wire                      clk,
    input  wire                      rst,
    input  wire [LANES-1:0]          in_valid,
    input  wire [LANES*CW-1:0]       ax, ay, bx, by,
    input  wire [LANES*ZW-1:0]       az, bz,
    input  wire [LANES*NW-1:0]       n,
    input  wire [LANES*MAXV*LA-1:0]  p_la, p_lb,
    input  wire [LANES*MAXV*LC-1:0]  p_lc,
    input  wire [LANES*MAXV*PX-1:0]  p_vx, p_vy,
    input  wire [LANES*MAXV*PW-1:0]  p_vw,
    input  wire [LANES*AW-1:0]       alpha, beta,
    input  wire [LANES*GW-1:0]       gamma,
    input  wire [LANES*PW-1:0]       area,
    output wire [LANES-1:0]          out_valid,
    output wire [LANES-1:0]          out_survives
);
  genvar l;
  generate
    for (l = 0; l < LANES; l = l + 1) begin : lane
      DepthTestLane #(.MAXV(MAXV), .ZW(ZW), .CW(CW), .LA(LA), .LC(LC), .PX(PX), .PW(PW), .AW(AW), .GW(GW), .NW(NW)) u (
          .clk(clk), .rst(rst), .in_valid(in_valid[l]),
          .ax(ax[l*CW +: CW]), .ay(ay[l*CW +: CW]), .bx(bx[l*CW +: CW]), .by(by[l*CW +: CW]),
          .az(az[l*ZW +: ZW]), .bz(bz[l*ZW +: ZW]), .n(n[l*NW +: NW]),
          .p_la(p_la[l*MAXV*LA +: MAXV*LA]), .p_lb(p_lb[l*MAXV*LA +: MAXV*LA]), .p_lc(p_lc[l*MAXV*LC +: MAXV*LC]),
          .p_vx(p_vx[l*MAXV*PX +: MAXV*PX]), .p_vy(p_vy[l*MAXV*PX +: MAXV*PX]), .p_vw(p_vw[l*MAXV*PW +: MAXV*PW]),
          .alpha(alpha[l*AW +: AW]), .beta(beta[l*AW +: AW]), .gamma(gamma[l*GW +: GW]), .area(area[l*PW +: PW]),
          .out_valid(out_valid[l]), .out_survives(out_survives[l]));
    end
  endgenerate
endmodule
