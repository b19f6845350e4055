// standard_samples(): the D3D11 standard patterns in FORMAT.md's convention.
#include <gtest/gtest.h>

#include <set>

#include "tilevis/trace.h"

namespace tilevis::trace {
namespace {

TEST(StandardSamples, OneSampleIsThePixelCentre) {
  EXPECT_EQ(standard_samples(1, 8), (std::vector<SamplePos>{{128, 128}}));
  EXPECT_EQ(standard_samples(1, 1), (std::vector<SamplePos>{{1, 1}}));
  EXPECT_EQ(standard_samples(1), standard_samples(1, 8));
}

TEST(StandardSamples, TwoSamples) {
  // D3D (4, 4), (-4, -4) in 1/16 from the centre.
  EXPECT_EQ(standard_samples(2, 8), (std::vector<SamplePos>{{192, 192}, {64, 64}}));
  EXPECT_EQ(standard_samples(2, 2), (std::vector<SamplePos>{{3, 3}, {1, 1}}));
}

TEST(StandardSamples, FourSamples) {
  // D3D (-2, -6), (6, -2), (-6, 2), (2, 6).
  EXPECT_EQ(standard_samples(4, 4), (std::vector<SamplePos>{{6, 2}, {14, 6}, {2, 10}, {10, 14}}));
  EXPECT_EQ(standard_samples(4, 3), (std::vector<SamplePos>{{3, 1}, {7, 3}, {1, 5}, {5, 7}}));
}

TEST(StandardSamples, EightAndSixteenFirstAndLast) {
  const auto s8 = standard_samples(8, 4);
  ASSERT_EQ(s8.size(), 8u);
  EXPECT_EQ(s8.front(), (SamplePos{9, 5}));   // D3D (1, -3)
  EXPECT_EQ(s8.back(), (SamplePos{15, 1}));   // D3D (7, -7)
  const auto s16 = standard_samples(16, 4);
  ASSERT_EQ(s16.size(), 16u);
  EXPECT_EQ(s16.front(), (SamplePos{9, 9}));  // D3D (1, 1)
  EXPECT_EQ(s16[8], (SamplePos{6, 14}));      // D3D (-2, 6)
  EXPECT_EQ(s16.back(), (SamplePos{1, 0}));   // D3D (-7, -8)
}

// The 8- and 16-sample patterns are "n-rooks": one sample in each of their rows and
// columns of the 1/16 (or, for 8, odd 1/16) grid. A mistyped table entry breaks this.
TEST(StandardSamples, EightAndSixteenHaveOneSamplePerRowAndColumn) {
  for (uint32_t count : {8u, 16u}) {
    std::set<uint16_t> xs, ys;
    for (const SamplePos& s : standard_samples(count, 4)) {
      xs.insert(s.x);
      ys.insert(s.y);
      if (count == 8) {
        EXPECT_EQ(s.x % 2, 1);
        EXPECT_EQ(s.y % 2, 1);
      }
    }
    EXPECT_EQ(xs.size(), count);
    EXPECT_EQ(ys.size(), count);
  }
}

TEST(StandardSamples, ScaleExactlyWithPrecision) {
  for (uint32_t count : {1u, 2u, 4u, 8u, 16u}) {
    const auto base = standard_samples(count, 4);
    for (uint32_t bits = 5; bits <= kMaxSubpixelBits; ++bits) {
      const auto scaled = standard_samples(count, bits);
      ASSERT_EQ(scaled.size(), base.size());
      for (size_t i = 0; i < base.size(); ++i) {
        EXPECT_EQ(scaled[i].x, base[i].x << (bits - 4));
        EXPECT_EQ(scaled[i].y, base[i].y << (bits - 4));
        EXPECT_LT(scaled[i].x, 1u << bits);
        EXPECT_LT(scaled[i].y, 1u << bits);
      }
    }
  }
}

TEST(StandardSamples, PassValidation) {
  for (uint32_t count : {1u, 2u, 4u, 8u, 16u}) {
    Trace trace;
    trace.frames.emplace_back();
    trace.frames[0].subpixel_bits = 4;
    trace.frames[0].samples = standard_samples(count, 4);
    EXPECT_NO_THROW(validate(trace)) << count;
  }
}

TEST(StandardSamples, RejectUnsupportedCounts) {
  for (uint32_t count : {0u, 3u, 5u, 32u}) EXPECT_THROW(standard_samples(count), std::invalid_argument) << count;
}

TEST(StandardSamples, RejectPrecisionsThatCannotHoldThePattern) {
  EXPECT_THROW(standard_samples(16, 3), std::invalid_argument);
  EXPECT_THROW(standard_samples(8, 3), std::invalid_argument);
  EXPECT_THROW(standard_samples(4, 2), std::invalid_argument);
  EXPECT_THROW(standard_samples(2, 1), std::invalid_argument);
  EXPECT_NO_THROW(standard_samples(2, 2));
  EXPECT_THROW(standard_samples(1, 0), std::invalid_argument);
  EXPECT_THROW(standard_samples(1, kMaxSubpixelBits + 1), std::invalid_argument);
}

}  // namespace
}  // namespace tilevis::trace
