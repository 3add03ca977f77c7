// Prints a measured figure from a test on both the host (gtest, stdout) and the target
// (minitest, the board console), so numbers quoted in docs/ can be re-read from any run.
#pragma once

#if defined(SEQSLAM_TEST_GTEST)
#include <cstdio>
#else
#include "minitest.h"
#endif

namespace seqslam::test {

// Prints "[ figure   ] <label> <value>" with ~9 significant digits.
inline void log_figure(const char* label, double value) {
#if defined(SEQSLAM_TEST_GTEST)
  std::printf("[ figure   ] %s %.9g\n", label, value);
#else
  minitest::internal::print_raw("[ figure   ] ");
  minitest::internal::print_raw(label);
  minitest::internal::print_raw(" ");
  minitest::internal::print(value);
  minitest::internal::print_raw("\n");
#endif
}

}  // namespace seqslam::test
