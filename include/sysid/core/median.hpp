#pragma once
/// @file
/// Purpose: the median of a set of numbers — one definition for every robust
/// statistic in the library (window floors, MAD scales, median time steps).
#include <algorithm>
#include <cstddef>
#include <numeric>
#include <stdexcept>
#include <vector>

namespace sysid {

/// The median of `values` (taken by value: reordered in place by nth_element,
/// O(n)); for an even count the mean of the two middle values.
/// Precondition (std::invalid_argument): values not empty.
inline double median(std::vector<double> values) {
  if (values.empty()) throw std::invalid_argument("median: need at least one value");
  const std::size_t n = values.size();
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(values.begin(), mid, values.end());
  if (n % 2 == 1) return *mid;
  // The lower middle value is the largest of those before `mid`. std::midpoint
  // rather than 0.5 * (a + b): the sum of two finite values can overflow (two
  // time steps of 1e308 gave an infinite median step; found by fuzz.csv).
  return std::midpoint(*std::max_element(values.begin(), mid), *mid);
}

}  // namespace sysid
