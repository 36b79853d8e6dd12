// The C++ tests' one assertion: CHECK(cond) reports a failed condition with its place and
// counts it in wmiltrack_test::failures, so that a test program runs every check and then
// exits non-zero if any failed (no test framework needed).
#pragma once

#include <cstdio>

namespace wmiltrack_test {
inline int failures = 0;
}  // namespace wmiltrack_test

#define CHECK(cond)                                                                  \
  do {                                                                               \
    if (!(cond)) {                                                                   \
      std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
      ++wmiltrack_test::failures;                                                    \
    }                                                                                \
  } while (0)
