// Exact predicates on clip-space (homogeneous) vertices, before any clipping or snap.
// Inputs are the trace's float32 values; every decision here is exact.
#pragma once

#include <cmath>

namespace tilevis::geom {

// Sign of det[[x0 y0 w0] [x1 y1 w1] [x2 y2 w2]] of three float32 clip-space vertices,
// exactly. Positive: the triangle turns counter-clockwise in NDC wherever it is in front of
// the eye, so its clipped, projected polygon is front-facing (OpenGL's facing of the
// clipped polygon, decided once for all its pieces: Olano & Greer, 2D homogeneous
// rasterization); zero: the eye lies in the triangle's plane and it projects to a line.
//
// Exactness: a product of two floats has at most 48 significant bits, so x*y is exact in
// double; (x*y)*w is split into p + e by an FMA (TwoProduct), also exact. Magnitudes stay
// within [2^-447, 2^384], so neither underflows nor overflows in double. The twelve
// doubles are summed into a non-overlapping expansion (Shewchuk's Grow-Expansion, each
// step a TwoSum), whose largest component carries the sign. Requires round-to-nearest
// and no contraction of the TwoSum steps (x86-64 has no FMA contraction without -mfma).
//
// A filter settles almost every triangle first: the six products rounded once each (relative
// error 2^-53) and summed in double (five roundings) are within 6.001 x 2^-53 of the total of
// their magnitudes of the exact determinant; a sum beyond 2^-48 of that total has its sign
// (cuda_ref's setup.cuh facing_filter, the same bound). Only the rest take the expansion.
inline int homogeneous_orientation(float x0, float y0, float w0, float x1, float y1, float w1, float x2, float y2,
                                   float w2) {
  {
    const double t[6] = {double(x0) * y1 * w2, -double(x0) * y2 * w1, double(x1) * y2 * w0,
                         -double(x1) * y0 * w2, double(x2) * y0 * w1, -double(x2) * y1 * w0};
    double sum = 0, mag = 0;
    for (double v : t) {
      sum += v;
      mag += std::fabs(v);
    }
    const double bound = mag * 0x1p-48;
    if (sum > bound) return 1;
    if (sum < -bound) return -1;
  }
  double h[12];
  int n = 0;
  auto add = [&](double t) {
    int m = 0;
    double q = t;
    for (int i = 0; i < n; ++i) {
      const double s = q + h[i];
      const double bv = s - q;
      const double err = (q - (s - bv)) + (h[i] - bv);
      q = s;
      if (err != 0) h[m++] = err;
    }
    if (q != 0) h[m++] = q;
    n = m;
  };
  auto term = [&](double a, double b, double c) {  // a * b * c, a b exact
    const double ab = a * b;
    const double p = ab * c;
    add(p);
    add(std::fma(ab, c, -p));
  };
  term(x0, y1, w2);
  term(-double(x0), y2, w1);
  term(x1, y2, w0);
  term(-double(x1), y0, w2);
  term(x2, y0, w1);
  term(-double(x2), y1, w0);
  return n == 0 ? 0 : (h[n - 1] > 0 ? 1 : -1);
}

}  // namespace tilevis::geom
