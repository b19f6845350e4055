// geom/homogeneous.h: the sign of det[x y w] of float32 vertices equals the exact rational
// determinant's, on random inputs over the whole float range, near-singular ones and zeros.
#include <cmath>
#include <random>

#include <boost/multiprecision/cpp_int.hpp>
#include <gtest/gtest.h>

#include "geom/homogeneous.h"

namespace {

using Z = boost::multiprecision::cpp_int;

// A float as an integer times 2^-200, exactly (frexp's exponent of a float is at least -148).
Z scaled(float v) {
  int e = 0;
  const double m = std::frexp(double(v), &e);
  const Z mant = Z(static_cast<int64_t>(std::ldexp(m, 30)));  // 24 significant bits fit
  return mant << (e - 30 + 200);
}

int exact_sign(const float (&v)[9]) {
  Z a[9];
  for (int i = 0; i < 9; ++i) a[i] = scaled(v[i]);
  const Z det = a[0] * (a[4] * a[8] - a[7] * a[5]) - a[3] * (a[1] * a[8] - a[7] * a[2]) +
                a[6] * (a[1] * a[5] - a[4] * a[2]);
  return det > 0 ? 1 : det < 0 ? -1 : 0;
}

int fast_sign(const float (&v)[9]) {
  return tilevis::geom::homogeneous_orientation(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]);
}

TEST(HomogeneousOrientation, EqualsTheExactDeterminantOverTheFloatRange) {
  std::mt19937_64 rng(20261123);
  std::uniform_real_distribution<float> u(-1, 1);
  std::uniform_int_distribution<int> ex(-140, 120);
  int zeros = 0;
  for (int n = 0; n < 20000; ++n) {
    float v[9];
    for (float& x : v) x = std::ldexp(u(rng), (n % 4 == 0) ? ex(rng) : ex(rng) / 8);
    if (n % 5 == 1) {  // near-singular: the third vertex almost a combination of the others
      const float s = u(rng), t = u(rng);
      for (int k = 0; k < 3; ++k) v[6 + k] = s * v[k] + t * v[3 + k];
    }
    if (n % 7 == 2) v[6] = v[7] = v[8] = 0;  // a vertex at the eye: det = 0
    if (n % 11 == 3)
      for (int k = 0; k < 3; ++k) v[3 + k] = v[k] * 2;  // two vertices on one ray: det = 0
    const int want = exact_sign(v);
    zeros += want == 0;
    ASSERT_EQ(fast_sign(v), want) << "case " << n;
  }
  EXPECT_GT(zeros, 3000);
}

TEST(HomogeneousOrientation, CounterClockwiseInNdcIsPositive) {
  const float ccw[9] = {0, 0, 1, 1, 0, 1, 0, 1, 1};  // (0,0) (1,0) (0,1), all at w = 1
  EXPECT_EQ(fast_sign(ccw), 1);
  const float behind[9] = {0, 0, -1, -1, 0, -1, 0, -1, -1};  // the same, scaled by w = -1: det flips
  EXPECT_EQ(fast_sign(behind), -1);
}

}  // namespace
