// Records the largest single heap allocation made through operator new, so a test can
// show that the reader does not size allocations by counts it has not checked.
#pragma once

#include <cstddef>

namespace tilevis::trace::test {

// Starts recording from zero; largest_allocation() reports the largest request since.
void reset_largest_allocation();
std::size_t largest_allocation();

}  // namespace tilevis::trace::test
