#pragma once

#include <cstdint>
#include <vector>

#include "tilevis/trace.h"

namespace tilevis::trace::detail {

// Lays out a trace that validate() has accepted.
std::vector<uint8_t> encode_valid(const Trace& trace);

}  // namespace tilevis::trace::detail
