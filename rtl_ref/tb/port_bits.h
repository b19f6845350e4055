// Packing signed integers into Verilated ports at a bit offset, and reading them back.
// A port of <= 8, 16, 32, 64 bits is an integer; wider ports are VlWide (32-bit words).
#pragma once

#include <algorithm>
#include <cstdint>
#include <type_traits>

#include "verilated.h"

namespace tilevis::rtl {

__extension__ typedef __int128 I128;
__extension__ typedef unsigned __int128 U128;

template <class T>
inline void put_bit(T& port, int bit, bool v) {
  if constexpr (std::is_integral_v<T>) {
    if (v)
      port |= T(T(1) << bit);
    else
      port &= T(~(T(1) << bit));
  } else {
    uint32_t& w = port[bit / 32];
    const uint32_t m = uint32_t(1) << (bit % 32);
    w = v ? (w | m) : (w & ~m);
  }
}

template <class T>
inline bool get_bit(const T& port, int bit) {
  if constexpr (std::is_integral_v<T>)
    return (port >> bit) & 1;
  else
    return (port[bit / 32] >> (bit % 32)) & 1;
}

// Two's complement of v in `width` bits (bits above 127 copy the sign). Wide ports are written
// a 32-bit word at a time.
template <class T>
inline void put_field(T& port, int lsb, int width, I128 v) {
  const U128 u = U128(v);
  // Bits i .. i + 63 of v's two's complement (sign-extended past bit 127).
  const auto bits = [&](int i) -> uint64_t {
    const uint64_t sign = v < 0 ? ~uint64_t(0) : 0;
    if (i >= 128) return sign;
    const uint64_t b = uint64_t(u >> i);
    return i > 64 ? b | (sign << (128 - i)) : b;
  };
  if constexpr (std::is_integral_v<T>) {
    for (int i = 0; i < width; ++i) put_bit(port, lsb + i, (bits(i) & 1) != 0);
  } else {
    for (int i = 0; i < width;) {
      const int bit = lsb + i, off = bit % 32, n = std::min(32 - off, width - i);
      const uint32_t mask = (n == 32 ? ~uint32_t(0) : (uint32_t(1) << n) - 1) << off;
      uint32_t& w = port[bit / 32];
      w = (w & ~mask) | ((uint32_t(bits(i)) << off) & mask);
      i += n;
    }
  }
}

template <class T>
inline uint64_t get_field(const T& port, int lsb, int width) {
  uint64_t r = 0;
  for (int i = 0; i < width; ++i) r |= uint64_t(get_bit(port, lsb + i)) << i;
  return r;
}

}  // namespace tilevis::rtl

namespace tilevis::rtl {

// A signed field of up to 128 bits, sign-extended.
template <class T>
inline I128 get_signed(const T& port, int lsb, int width) {
  U128 r = 0;
  for (int i = 0; i < width; ++i) r |= U128(get_bit(port, lsb + i)) << i;
  if (width < 128 && get_bit(port, lsb + width - 1)) r |= ~U128(0) << width;
  return I128(r);
}

}  // namespace tilevis::rtl
