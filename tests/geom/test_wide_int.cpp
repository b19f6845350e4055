#include <gtest/gtest.h>

#include <random>

#include "geom/wide_int.h"
#include "oracle.h"

namespace tilevis::geom::test {
namespace {

template <int L>
WideInt<L> random_wide(std::mt19937_64& rng, int bits) {
  // Uniform magnitude below 2^bits, random sign.
  WideInt<L> v{};
  for (int i = 0; i < L; ++i) v.limb[i] = rng();
  for (int i = 0; i < L; ++i) {
    const int lo = 64 * i;
    if (lo >= bits) v.limb[i] = 0;
    else if (bits - lo < 64) v.limb[i] &= (uint64_t{1} << (bits - lo)) - 1;
  }
  return (rng() & 1) ? -v : v;
}

template <int L>
void check_ops(uint64_t seed) {
  std::mt19937_64 rng(seed);
  const BigInt mod = BigInt(1) << (64 * L);
  for (int it = 0; it < 20000; ++it) {
    const int half = 32 * L - 1;
    const int ba = 1 + static_cast<int>(rng() % static_cast<uint64_t>(half));
    const int bb = 1 + static_cast<int>(rng() % static_cast<uint64_t>(half));
    const auto a = random_wide<L>(rng, ba);
    const auto b = random_wide<L>(rng, bb);
    const BigInt A = big(a), B = big(b);
    ASSERT_EQ(big(a + b), A + B);
    ASSERT_EQ(big(a - b), A - B);
    ASSERT_EQ(big(a * b), A * B);  // |A B| < 2^(64L - 2)
    ASSERT_EQ(big(-a), -A);
    ASSERT_EQ((a - b).sign(), sgn(A - B));
    ASSERT_TRUE(is_correctly_rounded(a.to_double(), A)) << A;
    (void)mod;
  }
}

TEST(WideInt, Ops192) { check_ops<3>(1); }
TEST(WideInt, Ops256) { check_ops<4>(2); }
TEST(WideInt, Ops320) { check_ops<5>(3); }

TEST(WideInt, FromNarrowSignExtends) {
  const Int128 v = -(Int128{1} << 100) + 12345;
  EXPECT_EQ(big(wide<5>(v)), big(v));
  EXPECT_EQ(big(wide<5>(wide<3>(v))), big(v));
  EXPECT_EQ(big(wide<4>(int64_t{-7})), BigInt(-7));
  EXPECT_EQ(wide<4>(int64_t{0}).sign(), 0);
  EXPECT_EQ(wide<4>(int64_t{-1}).sign(), -1);
}

TEST(WideInt, ToDoubleRoundsTiesToEven) {
  // 2^200 + 2^147: exactly halfway between two doubles (spacing 2^148), tie goes to even.
  const Int256 half_way = wide<4>(Int128{1} << 100) * wide<4>(Int128{1} << 100) +
                          wide<4>(Int128{1} << 100) * wide<4>(Int128{1} << 47);
  EXPECT_EQ(half_way.to_double(), std::ldexp(1.0, 200));
  const Int256 above = half_way + wide<4>(int64_t{1});
  EXPECT_EQ(above.to_double(), std::ldexp(1.0, 200) + std::ldexp(1.0, 148));
}

}  // namespace
}  // namespace tilevis::geom::test
