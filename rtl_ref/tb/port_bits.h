// Packing signed integers into Verilated ports at a bit offset, and reading them back.
// A port of <= 8, 16, 32, 64 bits is an integer; wider ports are VlWide (32-bit words).
#pragma once

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

// Two's complement of v in `width` bits (width <= 128; bits above 127 copy the sign).
template <class T>
inline void put_field(T& port, int lsb, int width, I128 v) {
  const U128 u = U128(v);
  for (int i = 0; i < width; ++i) put_bit(port, lsb + i, i < 128 ? ((u >> i) & 1) : v < 0);
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
