#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "geom/fixed.h"
#include "oracle.h"
#include "test_cases.h"

namespace tilevis::geom::test {
namespace {

constexpr float kUnit = 1.0f / 256.0f;

TEST(Snap, CoordRoundsHalfToEven) {
  EXPECT_EQ(snap_coord(0.5f * kUnit), 0);
  EXPECT_EQ(snap_coord(1.5f * kUnit), 2);
  EXPECT_EQ(snap_coord(2.5f * kUnit), 2);
  EXPECT_EQ(snap_coord(-0.5f * kUnit), 0);
  EXPECT_EQ(snap_coord(-1.5f * kUnit), -2);
  EXPECT_EQ(snap_coord(-2.5f * kUnit), -2);
  EXPECT_EQ(snap_coord(0.49f * kUnit), 0);
  EXPECT_EQ(snap_coord(0.51f * kUnit), 1);
  EXPECT_EQ(snap_coord(100.0f), 25600);
  EXPECT_EQ(snap_coord(-3.25f), -832);
}

TEST(Snap, CoordMatchesExactOracle) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> d(-40000.0f, 40000.0f);
  for (int i = 0; i < tilevis::test::cases(200000); ++i) {
    const float v = (i % 3 == 0) ? std::round(d(rng) * 512.0f) / 512.0f : d(rng);  // many exact ties
    const Rational scaled = exact(static_cast<double>(v)) * 256;
    BigInt fl = boost::multiprecision::numerator(scaled) / boost::multiprecision::denominator(scaled);
    if (Rational(fl) > scaled) fl -= 1;  // floor
    const Rational frac = scaled - Rational(fl);
    BigInt r = fl;
    if (frac > Rational(1, 2) || (frac == Rational(1, 2) && (fl & 1) != 0)) r += 1;
    const bool in_band = r > -(BigInt(1) << 23) && r < (BigInt(1) << 23);
    const auto got = snap_coord(v);
    ASSERT_EQ(got.has_value(), in_band) << v;
    if (in_band) {
      ASSERT_EQ(BigInt(*got), r) << v;
    }
  }
}

TEST(Snap, GuardBandIsReportedNotWrapped) {
  EXPECT_EQ(snap_coord(32767.0f), 32767 * 256);
  EXPECT_EQ(snap_coord(32767.99f), std::optional<int32_t>(static_cast<int32_t>(std::lround(32767.99f * 256.0f))));
  EXPECT_FALSE(snap_coord(32768.0f).has_value());
  EXPECT_FALSE(snap_coord(-32768.0f).has_value());
  // 8388607.5 sub-pixels ties to the even 2^23, which is outside the band.
  EXPECT_FALSE(snap_coord(8388607.5f / 256.0f).has_value());
  EXPECT_FALSE(snap_coord(1e30f).has_value());
  EXPECT_FALSE(snap_coord(-std::numeric_limits<float>::infinity()).has_value());
  EXPECT_FALSE(snap_coord(std::numeric_limits<float>::quiet_NaN()).has_value());
  EXPECT_FALSE(snap_vertex(1.0f, 40000.0f, 0.5f, 24).has_value());
  const auto v = snap_vertex(1.0f, 2.0f, 1.0f, 24);
  ASSERT_TRUE(v.has_value());
  EXPECT_EQ(*v, (Vertex{256, 512, (1u << 24) - 1}));
}

TEST(Snap, DepthRoundsAndClamps) {
  EXPECT_EQ(snap_depth(0.0f, 24), 0u);
  EXPECT_EQ(snap_depth(-0.5f, 24), 0u);
  EXPECT_EQ(snap_depth(std::numeric_limits<float>::quiet_NaN(), 24), 0u);
  EXPECT_EQ(snap_depth(1.0f, 24), (1u << 24) - 1);
  EXPECT_EQ(snap_depth(2.0f, 24), (1u << 24) - 1);
  EXPECT_EQ(snap_depth(1.0f, 32), 0xffffffffu);
  EXPECT_EQ(snap_depth(0.5f, 24), 1u << 23);   // 8388607.5 -> even 8388608
  EXPECT_EQ(snap_depth(0.5f, 32), 1u << 31);   // 2147483647.5 -> even 2^31
  EXPECT_EQ(snap_depth(0.25f, 16), 16384u);    // 16383.75
  EXPECT_EQ(snap_depth(1e-30f, 32), 0u);
  EXPECT_EQ(snap_depth(std::numeric_limits<float>::denorm_min(), 32), 0u);
}

TEST(Snap, DepthMatchesExactOracle) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<float> d(0.0f, 1.0f);
  for (int bits : {8, 16, 24, 29, 32}) {
    const BigInt max_value = (BigInt(1) << bits) - 1;
    for (int i = 0; i < tilevis::test::cases(50000); ++i) {
      float z = d(rng);
      if (i % 4 == 0) z = std::ldexp(z, -static_cast<int>(rng() % 40));
      const Rational scaled = exact(static_cast<double>(z)) * Rational(max_value);
      BigInt fl = boost::multiprecision::numerator(scaled) / boost::multiprecision::denominator(scaled);
      const Rational frac = scaled - Rational(fl);
      BigInt r = fl;
      if (frac > Rational(1, 2) || (frac == Rational(1, 2) && (fl & 1) != 0)) r += 1;
      ASSERT_EQ(BigInt(snap_depth(z, bits)), r) << z << " bits " << bits;
    }
  }
}

// Double inputs (the setup unit's viewport transform runs in double) and other sub-pixel
// precisions: same exact round-half-even oracle.
TEST(Snap, DoubleInputsAndSubpixelBits) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> d(-40000.0, 40000.0);
  for (int bits : {0, 4, 8}) {
    for (int i = 0; i < tilevis::test::cases(50000); ++i) {
      double v = d(rng);
      if (i % 3 == 0) v = std::round(v * 2.0 * (1 << bits)) / (2.0 * (1 << bits));  // exact ties
      const Rational scaled = exact(v) * (1 << bits);
      BigInt fl = boost::multiprecision::numerator(scaled) / boost::multiprecision::denominator(scaled);
      if (Rational(fl) > scaled) fl -= 1;
      const Rational frac = scaled - Rational(fl);
      BigInt r = fl;
      if (frac > Rational(1, 2) || (frac == Rational(1, 2) && (fl & 1) != 0)) r += 1;
      const bool in_band = r > -(BigInt(1) << 23) && r < (BigInt(1) << 23);
      const auto got = snap_coord(v, bits);
      ASSERT_EQ(got.has_value(), in_band) << v;
      if (in_band) {
        ASSERT_EQ(BigInt(*got), r) << v;
      }
    }
  }
  std::uniform_real_distribution<double> dz(0.0, 1.0);
  for (int bits : {16, 24, 32}) {
    const BigInt max_value = (BigInt(1) << bits) - 1;
    for (int i = 0; i < tilevis::test::cases(50000); ++i) {
      double z = dz(rng);
      if (i % 4 == 0) z = std::ldexp(z, -static_cast<int>(rng() % 80));
      if (i % 4 == 1) z = (std::round(z * static_cast<double>(max_value)) + 0.5) / static_cast<double>(max_value);
      const Rational scaled = exact(z) * Rational(max_value);
      BigInt fl = boost::multiprecision::numerator(scaled) / boost::multiprecision::denominator(scaled);
      const Rational frac = scaled - Rational(fl);
      BigInt r = fl;
      if (frac > Rational(1, 2) || (frac == Rational(1, 2) && (fl & 1) != 0)) r += 1;
      if (r > max_value) r = max_value;
      ASSERT_EQ(BigInt(snap_depth(z, bits)), r) << z << " bits " << bits;
    }
  }
  EXPECT_EQ(snap_depth(std::numeric_limits<double>::denorm_min(), 32), 0u);
  EXPECT_EQ(snap_depth(std::nextafter(1.0, 0.0), 32), 0xffffffffu);
}

TEST(Snap, TileRect) {
  EXPECT_EQ(tile_rect(2, 3, 32, 16), (Rect{2 * 32 * 256, 3 * 16 * 256, 3 * 32 * 256, 4 * 16 * 256}));
}

}  // namespace
}  // namespace tilevis::geom::test
