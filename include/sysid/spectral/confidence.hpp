#pragma once
/// @file
/// Purpose: the quantiles behind the confidence bounds of spectral estimates:
/// the standard normal quantile and the chi-square quantile, and the chi-square
/// confidence interval of a PSD estimate with nu equivalent degrees of freedom.
///
/// Method:
/// - normal quantile: bisection of Phi(z) = erfc(-z / sqrt 2) / 2 = p on [-40, 40]
///   followed by two Newton steps (Phi is monotone, so bisection cannot fail;
///   std::erfc is accurate to a few ulp, so the quantile is accurate to ~1e-14
///   for 1e-300 < p < 1 - 1e-16);
/// - chi-square quantile: Wilson & Hilferty, "The distribution of chi-square",
///   PNAS 17 (1931) 684-688: (X / nu)^(1/3) is nearly normal with mean
///   1 - 2/(9 nu) and variance 2/(9 nu), so
///   chi2_p(nu) ~ nu (1 - 2/(9 nu) + z_p sqrt(2/(9 nu)))^3.
///   Relative error below 1 % for nu >= 10 and 0.005 <= p <= 0.995, a few % at nu = 2
///   (the single periodogram); it is used for nu >= 2 only;
/// - PSD interval (Bendat & Piersol, Random Data, 4th ed., sec. 8.5.4; Percival &
///   Walden, Spectral Analysis for Physical Applications, 1993, eq. 292c):
///   nu S_hat / S ~ chi2(nu), so with probability `level`
///   nu S_hat / chi2_{(1+level)/2}(nu) <= S <= nu S_hat / chi2_{(1-level)/2}(nu).
#include <cmath>
#include <stdexcept>
#include <utility>

namespace sysid {

/// Standard normal quantile z with P(Z <= z) = p. Preconditions: 0 < p < 1.
inline double normal_quantile(double p) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("normal_quantile: need 0 < p < 1");
  const auto cdf = [](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
  double lo = -40.0, hi = 40.0;
  for (int it = 0; it < 200 && hi - lo > 1e-12; ++it) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < p ? lo : hi) = mid;
  }
  double z = 0.5 * (lo + hi);
  for (int it = 0; it < 2; ++it) {
    const double pdf = std::exp(-0.5 * z * z) / std::sqrt(2.0 * 3.14159265358979323846);
    if (pdf > 1e-300) z -= (cdf(z) - p) / pdf;
  }
  return z;
}

/// Chi-square quantile chi2_p(nu) (Wilson-Hilferty). Preconditions: 0 < p < 1, nu > 0.
inline double chi_square_quantile(double p, double nu) {
  if (!(nu > 0.0) || !std::isfinite(nu)) throw std::invalid_argument("chi_square_quantile: need 0 < nu < infinity");
  const double z = normal_quantile(p);
  const double c = 2.0 / (9.0 * nu);
  const double base = 1.0 - c + z * std::sqrt(c);
  // For tiny nu and small p the cube root base can go negative; the quantile is then ~0.
  return base > 0.0 ? nu * base * base * base : 0.0;
}

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
