#pragma once
/// @file
/// Purpose: the chi-square confidence interval of a PSD estimate with nu
/// equivalent degrees of freedom. The quantiles behind it (the standard normal
/// quantile, the Wilson-Hilferty chi-square quantile) are in core/distributions.hpp,
/// included here, with their method and accuracy.
///
/// Method:
/// - PSD interval (Bendat & Piersol, Random Data, 4th ed., sec. 8.5.4; Percival &
///   Walden, Spectral Analysis for Physical Applications, 1993, eq. 292c):
///   nu S_hat / S ~ chi2(nu), so with probability `level`
///   nu S_hat / chi2_{(1+level)/2}(nu) <= S <= nu S_hat / chi2_{(1-level)/2}(nu).
#include <sysid/core/distributions.hpp>

#include <cmath>
#include <stdexcept>
#include <utility>

namespace sysid {

/// Factors (lower, upper) such that [lower * S_hat, upper * S_hat] is the `level`
/// confidence interval of a PSD with nu equivalent degrees of freedom.
/// Preconditions: 0 < level < 1, nu > 0. The upper factor is +infinity when the
/// lower chi-square quantile is 0 (only for nu < ~0.5).
inline std::pair<double, double> psd_confidence_factors(double nu, double level) {
  if (!(level > 0.0 && level < 1.0)) throw std::invalid_argument("psd_confidence_factors: need 0 < level < 1");
  const double hi_q = chi_square_quantile(0.5 * (1.0 + level), nu);
  const double lo_q = chi_square_quantile(0.5 * (1.0 - level), nu);
  return {nu / hi_q, lo_q > 0.0 ? nu / lo_q : INFINITY};
}

}  // namespace sysid
