// Exec::sort_pairs driven from plain C++ code (tests/cuda's GPU test of every path the sort takes
// by size), so that the test needs neither nvcc nor Exec's header.
#pragma once

#include <cstdint>
#include <vector>

namespace tilevis::cuda {

// Sorts the pairs by the keys' bits under end_bit (stable), in place, on device 0 (gpu) or in
// the host emulation. With count < keys.size() the count is passed as a device count, as a
// device-sized run passes it: the keys from it on are padded (all ones) and every pair is sorted.
void sort_pairs_probe(bool gpu, std::vector<uint64_t>& keys, std::vector<uint32_t>& vals, int end_bit, uint64_t count);

}  // namespace tilevis::cuda
