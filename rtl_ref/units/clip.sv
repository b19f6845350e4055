// Clip: one split of a convex polygon by a silhouette edge's line, both sides kept (SVGPU
// §3.2.2; model/geom/clip.h's geom::split, canonical order included). LANES independent
// lanes. A lane holds no copy of the parent (it stays in the piece memory): the parent's n
// edges are streamed twice, one a clock. LOAD classifies each vertex against the line; only
// when the line crosses, EMIT takes the edges again and, on each edge i >= 1, emits the
// children's edges of the pair (i - 1, i) from the previous edge, held in registers, and the
// arriving one (its side recomputed as in LOAD); edge 0's vertex and side are held for the
// pair (n - 1, 0), emitted in the final clock with `done`. Up to two child edges per side per
// clock, in geom::split's order (the pair (i, i + 1) for i = 0..n-1):
//   clocks per split = 1 (start) + n (load, sides) + n (emit, only when the line crosses) + 1 (done).
// n is NW bits (n >= 3): the lane's only bound on a parent's size.
// `status`: 0 the line crosses (both children emitted), 1 the polygon is inside (the inside
// child is the parent unchanged, the outside one empty), 2 outside (the reverse); nothing is
// emitted for 1 and 2. `status` is valid from the clock after the last LOAD edge (the driver
// streams the parent again when it is 0) until the next split's LOAD ends. A new vertex is the parent line's crossing with the clip line,
// (l x l_i) with w > 0 (geom::intersect), or the parent's vertex where the line passes
// through it (its representation kept).
//
// Widths (model/geom/README.md): clip edge endpoints |x|,|y| <= 2^23 (CW = 25); lines
// |a|,|b| <= 2^24 (LA = 26), |c| <= 2^47 (LC = 49); implicit vertices |x|,|y| <= 2^72
// (PX = 74), 0 < w <= 2^49 (PW = 51); side a x + b y + c w < 2^98 (100 bits); intersection
// w = a1 b2 - a2 b1 <= 2^49, x = b1 c2 - b2 c1 <= 2^72. Asserted in simulation.
module ClipLane #(
    parameter int CW = 25, LA = 26, LC = 49, PX = 74, PW = 51,
    parameter int NW = 12
) (
    input  wire                 clk,
    input  wire                 rst,
    output wire                 ready,
    input  wire                 start,
    input  wire [NW-1:0]        n,
    input  wire signed [CW-1:0] ax, ay, bx, by,
    // the parent's edges in order, once for LOAD and, when the line crosses, again for EMIT
    input  wire                 e_valid,
    input  wire signed [LA-1:0] e_la, e_lb,
    input  wire signed [LC-1:0] e_lc,
    input  wire signed [PX-1:0] e_vx, e_vy,
    input  wire signed [PW-1:0] e_vw,
    // child edges, slot 0 before slot 1; inside child (o_in*) and outside child (o_out*)
    output reg  [1:0]           o_in_valid, o_out_valid,
    output reg  [2*LA-1:0]      o_in_la, o_in_lb, o_out_la, o_out_lb,
    output reg  [2*LC-1:0]      o_in_lc, o_out_lc,
    output reg  [2*PX-1:0]      o_in_vx, o_in_vy, o_out_vx, o_out_vy,
    output reg  [2*PW-1:0]      o_in_vw, o_out_vw,
    output reg                  done,
    output reg  [1:0]           status
);
  localparam int SW = 100;
  localparam logic [1:0] IDLE = 2'd0, LOAD = 2'd1, EMIT = 2'd2, FIN = 2'd3;

  reg [1:0] state;
  reg [NW-1:0] cnt, pn;
  reg signed [LA-1:0] la, lb;  // the clip line (Line::through(a, b))
  reg signed [LC-1:0] lc;
  reg any_pos, any_neg;
  // EMIT: the previous edge i - 1 (line, vertex, side), and edge 0's vertex and side for the
  // last pair. Sides: 2'b01 positive, 2'b11 negative, 2'b00 on the line.
  reg signed [LA-1:0] p_la, p_lb;
  reg signed [LC-1:0] p_lc;
  reg signed [PX-1:0] p_vx, p_vy, f_vx, f_vy;
  reg signed [PW-1:0] p_vw, f_vw;
  reg [1:0] p_side, f_side;

  assign ready = state == IDLE;

  // side of the arriving vertex
  wire signed [SW-1:0] side = SW'(la * e_vx) + SW'(lb * e_vy) + SW'(lc * e_vw);
  wire [1:0] side_code = side > 0 ? 2'b01 : side < 0 ? 2'b11 : 2'b00;

  // the pair (i, next): i the held previous edge; next the arriving edge, or edge 0 in FIN.
  // A crossing's status is 0 from the end of LOAD on.
  wire last = state == FIN;
  wire emit = (state == EMIT && e_valid && cnt != '0) || (last && status == 2'd0);
  wire signed [PX-1:0] vx_n = last ? f_vx : e_vx, vy_n = last ? f_vy : e_vy;
  wire signed [PW-1:0] vw_n = last ? f_vw : e_vw;
  wire [1:0] side_n = last ? f_side : side_code;
  // X = l x l_i (geom::intersect(l, l_i)), normalised to w > 0: the same point for l's flip
  wire signed [PX-1:0] xx = PX'(lb * p_lc) - PX'(p_lb * lc);
  wire signed [PX-1:0] xy = PX'(lc * p_la) - PX'(p_lc * la);
  wire signed [PW-1:0] xw = PW'(la * p_lb) - PW'(p_la * lb);
  wire xneg = xw < 0;
  wire signed [PX-1:0] nx = xneg ? -xx : xx, ny = xneg ? -xy : xy;
  wire signed [PW-1:0] nw = xneg ? -xw : xw;
  wire si_pos = p_side == 2'b01, si_neg = p_side == 2'b11;
  wire sn_pos = side_n == 2'b01, sn_neg = side_n == 2'b11;

  always @(posedge clk) begin
    if (rst) begin
      state <= IDLE;
      done <= 1'b0;
      o_in_valid <= '0;
      o_out_valid <= '0;
    end else begin
      done <= 1'b0;
      o_in_valid <= '0;
      o_out_valid <= '0;
      case (state)
        IDLE: if (start) begin
          la <= LA'(ay) - LA'(by);
          lb <= LA'(bx) - LA'(ax);
          lc <= LC'(ax * by) - LC'(ay * bx);
          pn <= n;
          cnt <= '0;
          any_pos <= 1'b0;
          any_neg <= 1'b0;
          state <= LOAD;
        end
        LOAD: if (e_valid) begin
          any_pos <= any_pos || side_code == 2'b01;
          any_neg <= any_neg || side_code == 2'b11;
          if (cnt + 1 == pn) begin
            cnt <= '0;
            // crosses: stream the parent again to emit; else one side is the parent, unchanged
            if ((any_pos || side_code == 2'b01) && (any_neg || side_code == 2'b11)) begin
              status <= 2'd0;
              state <= EMIT;
            end else begin
              status <= (any_neg || side_code == 2'b11) ? 2'd2 : 2'd1;
              state <= FIN;
            end
          end else cnt <= cnt + 1;
        end
        EMIT: if (e_valid) begin
          p_la <= e_la; p_lb <= e_lb; p_lc <= e_lc;
          p_vx <= e_vx; p_vy <= e_vy; p_vw <= e_vw;
          p_side <= side_code;
          if (cnt == '0) begin
            f_vx <= e_vx; f_vy <= e_vy; f_vw <= e_vw;
            f_side <= side_code;
          end
          if (cnt + 1 == pn) state <= FIN;
          else cnt <= cnt + 1;
        end
        FIN: begin
          done <= 1'b1;
          state <= IDLE;
        end
      endcase
      if (emit) begin
        // inside (sigma = +1): skip unless i or next is positive
        if (si_pos || sn_pos) begin
          o_in_valid[0] <= 1'b1;
          o_in_la[0 +: LA] <= p_la; o_in_lb[0 +: LA] <= p_lb; o_in_lc[0 +: LC] <= p_lc;
          o_in_vx[0 +: PX] <= si_neg ? nx : p_vx;
          o_in_vy[0 +: PX] <= si_neg ? ny : p_vy;
          o_in_vw[0 +: PW] <= si_neg ? nw : p_vw;
          if (!sn_pos) begin  // the edge leaves the positive block: the clip line follows
            o_in_valid[1] <= 1'b1;
            o_in_la[LA +: LA] <= la; o_in_lb[LA +: LA] <= lb; o_in_lc[LC +: LC] <= lc;
            o_in_vx[PX +: PX] <= sn_neg ? nx : vx_n;
            o_in_vy[PX +: PX] <= sn_neg ? ny : vy_n;
            o_in_vw[PW +: PW] <= sn_neg ? nw : vw_n;
          end
        end
        // outside (sigma = -1), clip line flipped
        if (si_neg || sn_neg) begin
          o_out_valid[0] <= 1'b1;
          o_out_la[0 +: LA] <= p_la; o_out_lb[0 +: LA] <= p_lb; o_out_lc[0 +: LC] <= p_lc;
          o_out_vx[0 +: PX] <= si_pos ? nx : p_vx;
          o_out_vy[0 +: PX] <= si_pos ? ny : p_vy;
          o_out_vw[0 +: PW] <= si_pos ? nw : p_vw;
          if (!sn_neg) begin
            o_out_valid[1] <= 1'b1;
            o_out_la[LA +: LA] <= -la; o_out_lb[LA +: LA] <= -lb; o_out_lc[LC +: LC] <= -lc;
            o_out_vx[PX +: PX] <= sn_pos ? nx : vx_n;
            o_out_vy[PX +: PX] <= sn_pos ? ny : vy_n;
            o_out_vw[PW +: PW] <= sn_pos ? nw : vw_n;
          end
        end
      end
    end
  end

`ifndef SYNTHESIS
  always @(posedge clk) if (!rst) begin
    if (state == IDLE && start) begin
      assert (n >= 3) else $error("Clip: polygon of fewer than 3 edges");
      assert (ax >= -(CW'(1) << 23) && ax <= (CW'(1) << 23) && ay >= -(CW'(1) << 23) && ay <= (CW'(1) << 23) &&
              bx >= -(CW'(1) << 23) && bx <= (CW'(1) << 23) && by >= -(CW'(1) << 23) && by <= (CW'(1) << 23))
        else $error("Clip: clip edge endpoint beyond 2^23");
    end
    if ((state == LOAD || state == EMIT) && e_valid) begin
      assert (e_vw > 0 && e_vw <= (PW'(1) << 49)) else $error("Clip: vertex w out of (0, 2^49]");
      assert (e_vx >= -(PX'(1) << 72) && e_vx <= (PX'(1) << 72) && e_vy >= -(PX'(1) << 72) && e_vy <= (PX'(1) << 72))
        else $error("Clip: vertex x, y beyond 2^72");
      assert (e_la >= -(LA'(1) << 24) && e_la <= (LA'(1) << 24) && e_lb >= -(LA'(1) << 24) && e_lb <= (LA'(1) << 24))
        else $error("Clip: line a, b beyond 2^24");
      assert (e_lc >= -(LC'(1) << 47) && e_lc <= (LC'(1) << 47)) else $error("Clip: line c beyond 2^47");
      assert (side > -(SW'(1) << 98) && side < (SW'(1) << 98)) else $error("Clip: side beyond 2^98");
    end
    if (emit) begin
      assert (nw <= (PW'(1) << 49)) else $error("Clip: intersection w beyond 2^49");
      assert (nx >= -(PX'(1) << 72) && nx <= (PX'(1) << 72) && ny >= -(PX'(1) << 72) && ny <= (PX'(1) << 72))
        else $error("Clip: intersection x, y beyond 2^72");
      assert (!((si_pos && sn_neg) || (si_neg && sn_pos)) || xw != 0)
        else $error("Clip: parallel lines at a crossing");
    end
  end
`endif
endmodule

// LANES ClipLanes side by side (ports flattened lane-major).
module Clip #(
    parameter int LANES = 1,
    parameter int CW = 25, LA = 26, LC = 49, PX = 74, PW = 51,
    parameter int NW = 12
) (
    input  wire                     clk,
    input  wire                     rst,
    output wire [LANES-1:0]         ready,
    input  wire [LANES-1:0]         start,
    input  wire [LANES*NW-1:0]      n,
    input  wire [LANES*CW-1:0]      ax, ay, bx, by,
    input  wire [LANES-1:0]         e_valid,
    input  wire [LANES*LA-1:0]      e_la, e_lb,
    input  wire [LANES*LC-1:0]      e_lc,
    input  wire [LANES*PX-1:0]      e_vx, e_vy,
    input  wire [LANES*PW-1:0]      e_vw,
    output wire [LANES*2-1:0]       o_in_valid, o_out_valid,
    output wire [LANES*2*LA-1:0]    o_in_la, o_in_lb, o_out_la, o_out_lb,
    output wire [LANES*2*LC-1:0]    o_in_lc, o_out_lc,
    output wire [LANES*2*PX-1:0]    o_in_vx, o_in_vy, o_out_vx, o_out_vy,
    output wire [LANES*2*PW-1:0]    o_in_vw, o_out_vw,
    output wire [LANES-1:0]         done,
    output wire [LANES*2-1:0]       status
);
  genvar l;
  generate
    for (l = 0; l < LANES; l = l + 1) begin : lane
      ClipLane #(.CW(CW), .LA(LA), .LC(LC), .PX(PX), .PW(PW), .NW(NW)) u (
          .clk(clk), .rst(rst), .ready(ready[l]), .start(start[l]), .n(n[l*NW +: NW]),
          .ax(ax[l*CW +: CW]), .ay(ay[l*CW +: CW]), .bx(bx[l*CW +: CW]), .by(by[l*CW +: CW]),
          .e_valid(e_valid[l]), .e_la(e_la[l*LA +: LA]), .e_lb(e_lb[l*LA +: LA]), .e_lc(e_lc[l*LC +: LC]),
          .e_vx(e_vx[l*PX +: PX]), .e_vy(e_vy[l*PX +: PX]), .e_vw(e_vw[l*PW +: PW]),
          .o_in_valid(o_in_valid[l*2 +: 2]), .o_out_valid(o_out_valid[l*2 +: 2]),
          .o_in_la(o_in_la[l*2*LA +: 2*LA]), .o_in_lb(o_in_lb[l*2*LA +: 2*LA]),
          .o_out_la(o_out_la[l*2*LA +: 2*LA]), .o_out_lb(o_out_lb[l*2*LA +: 2*LA]),
          .o_in_lc(o_in_lc[l*2*LC +: 2*LC]), .o_out_lc(o_out_lc[l*2*LC +: 2*LC]),
          .o_in_vx(o_in_vx[l*2*PX +: 2*PX]), .o_in_vy(o_in_vy[l*2*PX +: 2*PX]),
          .o_out_vx(o_out_vx[l*2*PX +: 2*PX]), .o_out_vy(o_out_vy[l*2*PX +: 2*PX]),
          .o_in_vw(o_in_vw[l*2*PW +: 2*PW]), .o_out_vw(o_out_vw[l*2*PW +: 2*PW]),
          .done(done[l]), .status(status[l*2 +: 2]));
    end
  endgenerate
endmodule
