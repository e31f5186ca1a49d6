#pragma once
// Shorter property tests under the sanitizers. The asan and tsan runs (tests/CMakeLists.txt) set
// AXON_TEST_SHORT=1 on their test shards: there the code runs 5-15x slower, and the few property
// tests that plan or brute-force hundreds of random cases took most of those stages (the proof
// property test alone 119 s under asan). With it set, such a test runs a quarter of its cases:
// every code path still runs under the sanitizer, and the Release run keeps the full count and the
// thresholds measured on it.

#include <algorithm>
#include <cstdlib>

namespace axon::test_support {

inline bool short_run() {
  const char* v = std::getenv("AXON_TEST_SHORT");
  return v != nullptr && *v != '\0' && *v != '0';
}

// How many of `full` random cases a property test runs: all of them, or a quarter under AXON_TEST_SHORT.
inline int cases(int full) { return short_run() ? std::max(1, full / 4) : full; }

}  // namespace axon::test_support
