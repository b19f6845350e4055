// Exec::sort_pairs against std::stable_sort of the keys' bits under end_bit, at sizes that take
// every path it has (the counting sort up to 8,192 pairs, CUB's device sort): keys with many ties, bits
// above end_bit that must not count, all-ones keys, and device counts padded to a bound.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "sort_probe.h"

namespace tilevis::cudatest {

inline void check_sort_pairs(bool gpu) {
  std::mt19937_64 rng(20261129);
  const auto check = [&](uint64_t n, int end_bit, uint64_t count) {  // count < n: a device count padded to n
    const uint64_t mask = end_bit >= 64 ? ~uint64_t{0} : (uint64_t{1} << end_bit) - 1;
    std::vector<uint64_t> keys(n);
    std::vector<uint32_t> vals(n);
    for (uint64_t i = 0; i < n; ++i) {
      keys[i] = (rng() % 61) | (rng() % 3 == 0 ? 0 : rng() << 40);  // 61 values: ties; bits above 40
      if (i % 97 == 5) keys[i] = ~uint64_t{0};
      vals[i] = uint32_t(i);
    }
    std::vector<uint64_t> got_k = keys;
    std::vector<uint32_t> got_v = vals;
    cuda::sort_pairs_probe(gpu, got_k, got_v, end_bit, count);
    for (uint64_t i = count; i < n; ++i) keys[i] = ~uint64_t{0};  // the padding
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return (keys[a] & mask) < (keys[b] & mask); });
    uint64_t wrong = 0;
    for (uint64_t i = 0; i < n; ++i) wrong += got_k[i] != keys[order[i]] || got_v[i] != vals[order[i]];
    EXPECT_EQ(wrong, 0u) << n << " pairs, end_bit " << end_bit << ", count " << count;
  };
  for (const uint64_t n : {1u, 37u, 2047u, 2048u, 2049u, 5374u, 8192u, 8193u, 16384u, 40000u})
    for (const int end_bit : {11, 35, 64}) check(n, end_bit, n);
  for (const uint64_t n : {100u, 5000u, 20000u}) check(n, 35, n - n / 4);
}

}  // namespace tilevis::cudatest
