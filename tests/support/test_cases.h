// How many cases a seeded random test runs. `./tilevis test` runs every test twice: in the
// Release build with all its cases, and under AddressSanitizer + UndefinedBehaviorSanitizer
// (TILEVIS_SANITIZE) to find memory errors and undefined behaviour. There a test runs the first
// quarter of the same seeded cases (same code paths, a fifth of the wall time at the sanitizers'
// 3-5x cost), so that the two builds' tests stay within CI's time.
#pragma once

namespace tilevis::test {

#ifdef TILEVIS_SANITIZED_TESTS
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

// The cases of a test that runs n of them in the Release build.
constexpr int cases(int n) { return kSanitized ? (n + 3) / 4 : n; }

}  // namespace tilevis::test
