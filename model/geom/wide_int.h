// Fixed-width two's-complement integers for the exact predicates whose bit bounds exceed
// __int128 (see README.md, "Predicates and bit bounds"). Plain 64-bit limbs, no heap, no
// branches on data in add/sub/mul, so the CUDA reference can mirror it limb for limb.
#pragma once

#include <cmath>
#include <cstdint>

namespace tilevis::geom {

// -Wpedantic rejects the bare keyword; __extension__ on the typedef is GCC/Clang's sanctioned way.
__extension__ typedef __int128 Int128;
__extension__ typedef unsigned __int128 UInt128;

// WideInt<L>: L little-endian 64-bit limbs, value range [-2^(64L-1), 2^(64L-1)).
// Arithmetic is modulo 2^(64L): a result is correct whenever the true value is in range,
// which every caller guarantees by a bound stated next to the call.
template <int L>
struct WideInt {
  static_assert(L >= 2 && L <= 8);
  uint64_t limb[L];

  static constexpr WideInt from(int64_t v) {
    WideInt r{};
    r.limb[0] = static_cast<uint64_t>(v);
    const uint64_t ext = v < 0 ? ~uint64_t{0} : 0;
    for (int i = 1; i < L; ++i) r.limb[i] = ext;
    return r;
  }

  static constexpr WideInt from(Int128 v) {
    WideInt r{};
    r.limb[0] = static_cast<uint64_t>(v);
    r.limb[1] = static_cast<uint64_t>(static_cast<UInt128>(v) >> 64);
    const uint64_t ext = v < 0 ? ~uint64_t{0} : 0;
    for (int i = 2; i < L; ++i) r.limb[i] = ext;
    return r;
  }

  template <int M>
  static constexpr WideInt from(const WideInt<M>& v) {
    static_assert(M <= L, "narrowing a WideInt is not a value-preserving conversion");
    WideInt r{};
    for (int i = 0; i < M; ++i) r.limb[i] = v.limb[i];
    const uint64_t ext = v.negative() ? ~uint64_t{0} : 0;
    for (int i = M; i < L; ++i) r.limb[i] = ext;
    return r;
  }

  constexpr bool negative() const { return (limb[L - 1] >> 63) != 0; }

  constexpr bool is_zero() const {
    uint64_t acc = 0;
    for (int i = 0; i < L; ++i) acc |= limb[i];
    return acc == 0;
  }

  constexpr int sign() const { return negative() ? -1 : (is_zero() ? 0 : 1); }

  friend constexpr WideInt operator+(const WideInt& a, const WideInt& b) {
    WideInt r{};
    uint64_t carry = 0;
    for (int i = 0; i < L; ++i) {
      const UInt128 t = static_cast<UInt128>(a.limb[i]) + b.limb[i] + carry;
      r.limb[i] = static_cast<uint64_t>(t);
      carry = static_cast<uint64_t>(t >> 64);
    }
    return r;
  }

  constexpr WideInt operator-() const {
    WideInt r{};
    uint64_t carry = 1;
    for (int i = 0; i < L; ++i) {
      const UInt128 t = static_cast<UInt128>(~limb[i]) + carry;
      r.limb[i] = static_cast<uint64_t>(t);
      carry = static_cast<uint64_t>(t >> 64);
    }
    return r;
  }

  friend constexpr WideInt operator-(const WideInt& a, const WideInt& b) { return a + (-b); }

  // Low L limbs of the product: two's-complement multiplication modulo 2^(64L) is the
  // unsigned one, so no sign handling is needed.
  friend constexpr WideInt operator*(const WideInt& a, const WideInt& b) {
    WideInt r{};
    for (int i = 0; i < L; ++i) {
      uint64_t carry = 0;
      for (int j = 0; i + j < L; ++j) {
        const UInt128 t = static_cast<UInt128>(a.limb[i]) * b.limb[j] + r.limb[i + j] + carry;
        r.limb[i + j] = static_cast<uint64_t>(t);
        carry = static_cast<uint64_t>(t >> 64);
      }
    }
    return r;
  }

  friend constexpr bool operator==(const WideInt& a, const WideInt& b) {
    for (int i = 0; i < L; ++i)
      if (a.limb[i] != b.limb[i]) return false;
    return true;
  }

  // Correctly rounded (to nearest) conversion: the top 128 bits with a sticky bit for the
  // rest are converted by the compiler's correctly rounded __int128 conversion.
  double to_double() const {
    const bool neg = negative();
    const WideInt m = neg ? -*this : *this;  // |min| never occurs: callers stay inside bounds
    int top = L - 1;
    while (top > 0 && m.limb[top] == 0) --top;
    double r;
    if (top <= 1) {
      r = static_cast<double>((static_cast<UInt128>(m.limb[1]) << 64) | m.limb[0]);
    } else {
      UInt128 head = (static_cast<UInt128>(m.limb[top]) << 64) | m.limb[top - 1];
      uint64_t sticky = 0;
      for (int i = 0; i < top - 1; ++i) sticky |= m.limb[i];
      // head has >= 65 significant bits, so a sticky bit in bit 0 decides ties correctly.
      head |= sticky != 0 ? 1 : 0;
      r = std::ldexp(static_cast<double>(head), 64 * (top - 1));
    }
    return neg ? -r : r;
  }
};

using Int192 = WideInt<3>;
using Int256 = WideInt<4>;
using Int320 = WideInt<5>;

template <int L>
constexpr WideInt<L> wide(int64_t v) { return WideInt<L>::from(v); }
template <int L>
constexpr WideInt<L> wide(Int128 v) { return WideInt<L>::from(v); }
template <int L, int M>
constexpr WideInt<L> wide(const WideInt<M>& v) { return WideInt<L>::from(v); }

}  // namespace tilevis::geom
