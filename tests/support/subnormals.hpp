#pragma once
// Checks for the tests of core/flush_subnormals.hpp and of the recursions it guards.
#include <Eigen/Dense>

#include <limits>

namespace sysid::test {

/// Whether any entry of `y` is subnormal (non-zero and below the smallest normal number).
inline bool has_subnormal(const Eigen::MatrixXd& y) {
  return (y.array() != 0.0 && y.array().abs() < std::numeric_limits<double>::min()).any();
}

/// Whether this thread flushes subnormal results to zero now: half the smallest
/// normal number comes out zero. volatile: the compiler must not fold the
/// product at compile time, where the run-time mode does not apply.
inline bool flushing_subnormals() {
  volatile double smallest = std::numeric_limits<double>::min();
  volatile double half = 0.5;
  return smallest * half == 0.0;
}

}  // namespace sysid::test
