// Integer and floating-point building blocks of the exact predicates, usable on host and
// device. cuda_ref shares no geometry code with model/: these are its own.
//
//  - I128 / U128: CUDA supports __int128 in device code (sm_90 target); products of two
//    int64 are taken in I128 with one widening multiply.
//  - Wide<L>: L little-endian 64-bit limbs, two's complement, arithmetic modulo 2^(64L).
//    Every caller states a bound that keeps its true value inside [-2^(64L-1), 2^(64L-1)).
//  - Correctly rounded conversions to double, so that floating-point filters and the
//    double-valued visible area agree bit for bit with any other correctly rounded code.
//  - dadd/dmul/ddiv (and fmul/fadd in float): IEEE round-to-nearest operations that nvcc never
//    contracts into FMA (the setup transform must reproduce the host's double arithmetic
//    exactly; the float lines, approx.cuh, must keep a point on a line on it).
#pragma once

#include <cmath>
#include <cstdint>

#if defined(__CUDACC__)
#define TV_HD __host__ __device__
#define TV_DEV __device__
#else
#define TV_HD
#define TV_DEV
#endif

namespace tilevis::cuda {

// Bit counts of a 32-bit word, on the device and on the host.
TV_HD inline uint32_t popc(uint32_t v) {
#if defined(__CUDA_ARCH__)
  return __popc(v);
#else
  return uint32_t(__builtin_popcount(v));
#endif
}

TV_HD inline int ctz32(uint32_t v) {  // v != 0
#if defined(__CUDA_ARCH__)
  return __ffs(v) - 1;
#else
  return __builtin_ctz(v);
#endif
}

__extension__ typedef __int128 I128;
__extension__ typedef unsigned __int128 U128;

// ---- floating point without contraction ---------------------------------------------------

// Products and sums each rounded to float, never fused: a fused a x + b y keeps the rounding
// error of one product, so a point exactly on a line (a x = -b y, whose rounded products cancel
// exactly) got a tiny nonzero side. On the device that made slivers' fan of needles, whose
// edges share vertices, split pieces along lines through their own vertices (GPU float: 11,659
// candidate pairs and 17,307 clips against the host emulation's 10,618 and 11,021) and its
// longest clip chains 3x exact's. Also the host emulation's arithmetic (no FMA there).
TV_HD inline float fmul(float a, float b) {
#if defined(__CUDA_ARCH__)
  return __fmul_rn(a, b);
#else
  return a * b;
#endif
}
TV_HD inline float fadd(float a, float b) {
#if defined(__CUDA_ARCH__)
  return __fadd_rn(a, b);
#else
  return a + b;
#endif
}
TV_HD inline double dadd(double a, double b) {
#if defined(__CUDA_ARCH__)
  return __dadd_rn(a, b);
#else
  return a + b;
#endif
}

TV_HD inline double dsub(double a, double b) {
#if defined(__CUDA_ARCH__)
  return __dsub_rn(a, b);
#else
  return a - b;
#endif
}
TV_HD inline double dmul(double a, double b) {
#if defined(__CUDA_ARCH__)
  return __dmul_rn(a, b);
#else
  return a * b;
#endif
}
TV_HD inline double ddiv(double a, double b) {
#if defined(__CUDA_ARCH__)
  return __ddiv_rn(a, b);
#else
  return a / b;
#endif
}
TV_HD inline double dabs(double a) { return a < 0 ? -a : a; }
TV_HD inline double dfma(double a, double b, double c) {
#if defined(__CUDA_ARCH__)
  return __fma_rn(a, b, c);
#else
  return std::fma(a, b, c);
#endif
}

// 2^e for |e| < 1023, exactly.
TV_HD inline double pow2(int e) {
  uint64_t bits = uint64_t(e + 1023) << 52;
  double r;
  static_assert(sizeof(r) == sizeof(bits));
  __builtin_memcpy(&r, &bits, sizeof(r));
  return r;
}

// What m dadd(x, a) in a row give, in a few steps per binade crossed: a is a power of two (a
// sample's share of a pixel), x >= 0. In x's binade [2^(e-1), 2^e) every double is a multiple
// of the ulp u = 2^(e-53); a >= u is a multiple of u too, so the additions are exact until the
// sum reaches 2^e, where one rounded addition crosses over. With a < u an addition gives x
// again (stuck from then on), or once x + u (a = u / 2, ties to even). top, u and 1 / a are
// powers of two taken from the exponents, and top - x is exact (top / 2 <= x < top), so
// (top - x) / a is one exact product: no frexp, ldexp or division (the GPU's double division
// is a sequence of dozens of instructions, and slivers' hybrid fold made 124 of these steps in a
// run). Below 2^-968 or from 2^1022 a step is one addition.
TV_HD inline double add_repeated(double x, double a, uint64_t m) {
  uint64_t abits;
  __builtin_memcpy(&abits, &a, 8);
  const double inv_a = pow2(1023 - int(abits >> 52));  // a = 2^(exponent - 1023)
  while (m != 0) {
    uint64_t xbits;
    __builtin_memcpy(&xbits, &x, 8);
    const int ex = int(xbits >> 52) - 1023;  // x in [2^ex, 2^(ex+1)) (x > 0, sign 0)
    if (!(x > 0) || ex < -968 || ex > 1021) {  // 0 (a negative sum cannot occur), or far out
      x = dadd(x, a);
      --m;
      continue;
    }
    const double top = pow2(ex + 1), u = pow2(ex - 52);
    if (a < u) {
      const double y = dadd(x, a);
      --m;
      if (y == x) return x;
      x = y;
      continue;
    }
    const uint64_t below = uint64_t(ceil(dmul(dsub(top, x), inv_a))) - 1;  // additions that stay under top
    if (below >= m) return dadd(x, dmul(double(m), a));
    x = dadd(dadd(x, dmul(double(below), a)), a);  // exact, then the one that crosses top
    m -= below + 1;
  }
  return x;
}

TV_HD inline int clz64(uint64_t v) {
#if defined(__CUDA_ARCH__)
  return __clzll(static_cast<long long>(v));
#else
  return v == 0 ? 64 : __builtin_clzll(v);
#endif
}

// Correctly rounded uint64 -> double (round to nearest, ties to even).
TV_HD inline double u64_to_double(uint64_t v) {
#if defined(__CUDA_ARCH__)
  return __ull2double_rn(static_cast<unsigned long long>(v));
#else
  return static_cast<double>(v);  // x86-64 and AArch64 conversions round to nearest
#endif
}

// Correctly rounded unsigned 128-bit -> double: the top 64 bits with a sticky bit for the
// rest (64 >= 53 + 2, so the sticky bit decides ties exactly as the full value would).
TV_HD inline double u128_to_double(U128 m) {
  const uint64_t hi = static_cast<uint64_t>(m >> 64);
  if (hi == 0) return u64_to_double(static_cast<uint64_t>(m));
  const int n = clz64(hi);
  const U128 s = m << n;
  uint64_t top = static_cast<uint64_t>(s >> 64);
  top |= static_cast<uint64_t>(s) != 0 ? 1u : 0u;
  return dmul(u64_to_double(top), pow2(64 - n));
}

TV_HD inline double i128_to_double(I128 v) {
  return v < 0 ? -u128_to_double(-static_cast<U128>(v)) : u128_to_double(static_cast<U128>(v));
}

TV_HD inline double i64_to_double(int64_t v) {
#if defined(__CUDA_ARCH__)
  return __ll2double_rn(static_cast<long long>(v));
#else
  return static_cast<double>(v);
#endif
}

TV_HD inline int sign64(int64_t v) { return (v > 0) - (v < 0); }
TV_HD inline int sign128(I128 v) { return (v > 0) - (v < 0); }
TV_HD inline I128 mul64(int64_t a, int64_t b) { return I128{a} * b; }

// ---- fixed-width wide integers ----------------------------------------------------------

template <int L>
struct Wide {
  uint64_t limb[L];

  TV_HD static Wide of(int64_t v) {
    Wide r;
    r.limb[0] = static_cast<uint64_t>(v);
    const uint64_t ext = v < 0 ? ~uint64_t{0} : 0;
    for (int i = 1; i < L; ++i) r.limb[i] = ext;
    return r;
  }
  TV_HD static Wide of(I128 v) {
    Wide r;
    r.limb[0] = static_cast<uint64_t>(v);
    r.limb[1] = static_cast<uint64_t>(static_cast<U128>(v) >> 64);
    const uint64_t ext = v < 0 ? ~uint64_t{0} : 0;
    for (int i = 2; i < L; ++i) r.limb[i] = ext;
    return r;
  }
  template <int M>
  TV_HD static Wide of(const Wide<M>& v) {
    static_assert(M <= L);
    Wide r;
    for (int i = 0; i < M; ++i) r.limb[i] = v.limb[i];
    const uint64_t ext = v.negative() ? ~uint64_t{0} : 0;
    for (int i = M; i < L; ++i) r.limb[i] = ext;
    return r;
  }

  TV_HD bool negative() const { return (limb[L - 1] >> 63) != 0; }
  TV_HD int sign() const {
    if (negative()) return -1;
    uint64_t acc = 0;
    for (int i = 0; i < L; ++i) acc |= limb[i];
    return acc != 0;
  }

  TV_HD friend Wide operator+(const Wide& a, const Wide& b) {
    Wide r;
    uint64_t carry = 0;
    for (int i = 0; i < L; ++i) {
      const uint64_t s = a.limb[i] + carry;
      const uint64_t c1 = s < carry;
      r.limb[i] = s + b.limb[i];
      carry = c1 + (r.limb[i] < s);
    }
    return r;
  }
  TV_HD Wide operator-() const {
    Wide r;
    uint64_t carry = 1;
    for (int i = 0; i < L; ++i) {
      r.limb[i] = ~limb[i] + carry;
      carry = carry && r.limb[i] == 0;
    }
    return r;
  }
  TV_HD friend Wide operator-(const Wide& a, const Wide& b) { return a + (-b); }

  // Low L limbs of the product (two's complement modulo 2^(64L) equals unsigned).
  TV_HD friend Wide operator*(const Wide& a, const Wide& b) {
    Wide r;
    for (int i = 0; i < L; ++i) r.limb[i] = 0;
    for (int i = 0; i < L; ++i) {
      uint64_t carry = 0;
      for (int j = 0; i + j < L; ++j) {
        const U128 t = static_cast<U128>(a.limb[i]) * b.limb[j] + r.limb[i + j] + carry;
        r.limb[i + j] = static_cast<uint64_t>(t);
        carry = static_cast<uint64_t>(t >> 64);
      }
    }
    return r;
  }

  // Correctly rounded to nearest: the leading 64 bits plus a sticky bit.
  TV_HD double to_double() const {
    const bool neg = negative();
    const Wide m = neg ? -*this : *this;
    int top = L - 1;
    while (top > 0 && m.limb[top] == 0) --top;
    double r;
    if (top <= 1) {
      r = u128_to_double((static_cast<U128>(m.limb[1]) << 64) | m.limb[0]);
    } else {
      const int n = clz64(m.limb[top]);
      // 128 bits starting at the leading one, then everything below is sticky.
      U128 head = (static_cast<U128>(m.limb[top]) << 64) | m.limb[top - 1];
      uint64_t below = m.limb[top - 2];
      if (n > 0) {
        head = (head << n) | (below >> (64 - n));
        below <<= n;
      }
      uint64_t sticky = below;
      for (int i = 0; i < top - 2; ++i) sticky |= m.limb[i];
      uint64_t top64 = static_cast<uint64_t>(head >> 64);
      top64 |= (static_cast<uint64_t>(head) | sticky) != 0 ? 1u : 0u;
      r = dmul(u64_to_double(top64), pow2(64 * top - n));
    }
    return neg ? -r : r;
  }
};

using W192 = Wide<3>;
using W256 = Wide<4>;
using W320 = Wide<5>;

template <int L>
TV_HD inline Wide<L> wide(int64_t v) { return Wide<L>::of(v); }
template <int L>
TV_HD inline Wide<L> wide(I128 v) { return Wide<L>::of(v); }
template <int L, int M>
TV_HD inline Wide<L> wide(const Wide<M>& v) { return Wide<L>::of(v); }

}  // namespace tilevis::cuda
