#pragma once
/// @file
/// Helpers shared by the fuzz targets: a property violation must stop the fuzzer
/// with a message (abort() is what libFuzzer reports as a crash and saves the
/// input for), and doubles are compared bit for bit, as the readers promise
/// bit-exact round trips.
#include <Eigen/Dense>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace sysid::fuzz {

[[noreturn]] inline void property_violated(const std::string& what) {
  std::fprintf(stderr, "fuzz property violated: %s\n", what.c_str());
  std::abort();
}

inline void check(bool ok, const std::string& what) {
  if (!ok) property_violated(what);
}

/// Same double, bit for bit; any two NaNs count as equal (text has no payloads).
inline bool same_bits(double a, double b) {
  if (std::isnan(a) && std::isnan(b)) return true;
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

inline bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return false;
  for (Eigen::Index k = 0; k < a.size(); ++k)
    if (!same_bits(a.data()[k], b.data()[k])) return false;
  return true;
}

}  // namespace sysid::fuzz
