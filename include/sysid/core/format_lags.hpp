#pragma once
/// @file
/// Purpose: lists of lags in words, for the verdicts of the residual and
/// correlation tests and the reports that print them ("autocorrelation outside
/// the 99 % bound at lags 1..3, 7"): validate/residual_analysis.hpp's verdicts and
/// `sysid resid` word their findings the same way.
#include <Eigen/Core>

#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

namespace sysid {

// In detail: helpers of the verdicts' wording (validate and `sysid resid`), not a
// general formatting API.
namespace detail {

/// "3, 7" / "-2..4" / "1..3, 7": runs of three or more consecutive lags as ranges.
inline std::string format_lags(const std::vector<Eigen::Index>& lags) {
  std::string s;
  for (std::size_t i = 0; i < lags.size();) {
    std::size_t j = i;
    while (j + 1 < lags.size() && lags[j + 1] == lags[j] + 1) ++j;
    if (!s.empty()) s += ", ";
    if (j - i >= 2) {
      s += std::to_string(lags[i]) + ".." + std::to_string(lags[j]);
    } else {
      for (std::size_t k = i; k <= j; ++k) s += (k > i ? ", " : "") + std::to_string(lags[k]);
    }
    i = j + 1;
  }
  return s;
}

/// "lag " before one lag, "lags " before several.
inline std::string lag_word(const std::vector<Eigen::Index>& lags) { return lags.size() == 1 ? "lag " : "lags "; }

/// A confidence level as a percentage: 0.99 -> "99 %" (printf "%g").
inline std::string percent(double confidence) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g %%", 100.0 * confidence);
  return buf;
}

}  // namespace detail

}  // namespace sysid
