// Why do two id buffers disagree? Classifies each mismatched sample by the geometry of
// the two triangles involved, so that a golden-vs-truth disagreement is never left
// unexplained (issue: "every remaining mismatch is explained by its cause").
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "visibility/setup.h"

namespace tilevis::vis {

struct MismatchReport {
  std::map<std::string, uint64_t> kinds;  // cause -> mismatched samples
  uint64_t mismatched = 0;
  std::vector<std::string> examples;      // a few, one line each
};

// a and b: per-sample ids of two producers over the same setup (same size).
MismatchReport explain_mismatches(const Setup& setup, const std::vector<int32_t>& a, const std::vector<int32_t>& b);

}  // namespace tilevis::vis
