#pragma once
// Test support: small checks shared by several test files.
#include <Eigen/Dense>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace sysid::test {

/// Whether one of `warnings` contains `text`.
inline bool has_warning(const std::vector<std::string>& warnings, const std::string& text) {
  for (const std::string& w : warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}

/// sqrt(sum ||a_k - b_k||^2 / sum ||b_k||^2) over the first `count` terms of two
/// matrix sequences (Markov parameters).
inline double relative_error(const std::vector<Eigen::MatrixXd>& a, const std::vector<Eigen::MatrixXd>& b,
                             std::size_t count) {
  double num = 0.0, den = 0.0;
  for (std::size_t k = 0; k < count; ++k) {
    num += (a[k] - b[k]).squaredNorm();
    den += b[k].squaredNorm();
  }
  return std::sqrt(num / den);
}

}  // namespace sysid::test
