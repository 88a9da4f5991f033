// Tests of core/distributions.hpp: the normal and chi-square quantiles, the
// incomplete gamma function and the chi-square distribution, the incomplete beta
// function with the Beta and F distributions, digamma and trigamma, the Tracy-Widom
// law and the largest canonical correlation; against closed
// forms, exact finite sums and table values (SciPy, Abramowitz & Stegun).
#include <sysid/core/distributions.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "random_matrices.hpp"

namespace test_unit_core_distributions {

using namespace sysid;

namespace {

/// Q(n, x) for integer n: e^{-x} sum_{k<n} x^k / k! (Abramowitz & Stegun 6.5.13).
double q_integer(int n, double x) {
  double term = 1.0, sum = 1.0;
  for (int k = 1; k < n; ++k) {
    term *= x / k;
    sum += term;
  }
  return std::exp(-x) * sum;
}

/// Q(k + 1/2, x) = erfc(sqrt x) + e^{-x} sum_{j<k} x^{j+1/2} / Gamma(j + 3/2) (A&S 6.5.13 with 6.5.22 recurrence).
double q_half_integer(int k, double x) {
  double s = std::erfc(std::sqrt(x));
  for (int j = 0; j < k; ++j) s += std::exp(-x + (j + 0.5) * std::log(x) - std::lgamma(j + 1.5));
  return s;
}

}  // namespace

// ---- the normal and chi-square quantiles -----------------------------------------

TEST(DistributionsNormalChiSquareQuantiles, MatchTables) {
  // Normal quantiles to 1e-9 (exact inversion of erfc).
  EXPECT_NEAR(normal_quantile(0.975), 1.959963984540054, 1e-9);
  EXPECT_NEAR(normal_quantile(0.995), 2.575829303548901, 1e-9);
  EXPECT_NEAR(normal_quantile(0.5), 0.0, 1e-12);
  // Chi-square table values (Abramowitz & Stegun 26.4); Wilson-Hilferty is within 0.1 % at nu = 100
  // and within 1 % at nu = 10.
  EXPECT_NEAR(chi_square_quantile(0.975, 100) / 129.5612, 1.0, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.025, 100) / 74.2219, 1.0, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.975, 10) / 20.4832, 1.0, 1e-2);
  EXPECT_NEAR(chi_square_quantile(0.025, 10) / 3.24697, 1.0, 1e-2);
}

TEST(DistributionsNormalChiSquareQuantiles, ConsistentWithTheTails) {
  // 1 dof: P(X > z^2) = P(|Z| > z), so chi_square_sf(z_{1-a/2}^2, 1) = a: the
  // bisection-and-Newton quantile against the continued fraction, both ~1e-14
  // (a >= 1e-4: 1 - a/2 itself carries a relative error eps / (a/2) in a).
  for (double a : {0.5, 0.05, 0.01, 1e-4}) {
    const double z = normal_quantile(1.0 - a / 2.0);
    EXPECT_NEAR(chi_square_sf(z * z, 1.0) / a, 1.0, 1e-9) << a;
  }
  // Symmetry of the normal quantile (1 - p rounds to a tail of relative error eps / p).
  for (double p : {1e-6, 0.01, 0.3}) EXPECT_NEAR(normal_quantile(p), -normal_quantile(1.0 - p), 1e-15 / p) << p;
  // Wilson-Hilferty against the exact CDF: P(X <= chi2_p) is p within 1e-3 for
  // nu >= 10 (largest miss 7e-4, at nu = 10, p = 0.01), within 1e-4 at nu = 100.
  for (double nu : {10.0, 25.0, 100.0})
    for (double p : {0.01, 0.5, 0.99}) {
      const double q = chi_square_quantile(p, nu);
      EXPECT_NEAR(chi_square_cdf(q, nu), p, nu >= 100.0 ? 1e-4 : 1e-3) << nu << " " << p;
    }
  // Tiny nu, small p: the cube's base goes negative and the quantile is 0.
  EXPECT_EQ(chi_square_quantile(1e-6, 0.05), 0.0);
}

TEST(DistributionsNormalChiSquareQuantiles, BadArgumentsThrow) {
  EXPECT_THROW(normal_quantile(1.0), std::invalid_argument);
  EXPECT_THROW(normal_quantile(0.0), std::invalid_argument);
  EXPECT_THROW(normal_quantile(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_THROW(chi_square_quantile(0.5, 0.0), std::invalid_argument);
  EXPECT_THROW(chi_square_quantile(0.5, std::numeric_limits<double>::infinity()), std::invalid_argument);
}

// ---- the incomplete gamma function and the chi-square distribution ---------------

TEST(DistributionsIncompleteGamma, ClosedFormsForSmallShapes) {
  // P(1, x) = 1 - e^{-x}; P(1/2, x) = erf(sqrt x) (A&S 6.5.17). Both branches
  // (series x < a + 1, continued fraction beyond) are exercised.
  for (double x : {1e-8, 1e-3, 0.3, 1.0, 1.99, 2.01, 5.0, 30.0}) {
    EXPECT_NEAR(regularized_gamma_p(1.0, x), -std::expm1(-x), 1e-15 + 2e-14 * -std::expm1(-x)) << x;
    EXPECT_NEAR(regularized_gamma_q(1.0, x) / std::exp(-x), 1.0, 1e-13) << x;
    EXPECT_NEAR(regularized_gamma_p(0.5, x), std::erf(std::sqrt(x)), 1e-14) << x;
    EXPECT_NEAR(regularized_gamma_q(0.5, x) / std::erfc(std::sqrt(x)), 1.0, 1e-12) << x;
  }
  EXPECT_EQ(regularized_gamma_p(3.0, 0.0), 0.0);
  EXPECT_EQ(regularized_gamma_q(3.0, 0.0), 1.0);
  EXPECT_EQ(regularized_gamma_p(3.0, std::numeric_limits<double>::infinity()), 1.0);
}

TEST(DistributionsIncompleteGamma, IntegerAndHalfIntegerShapesAgainstFiniteSums) {
  // The finite sums are exact formulas evaluated with positive terms (relative
  // error ~ n eps); the tolerance 1e-11 relative allows for the prefactor
  // exp(a ln x - x - lnGamma(a)), whose argument of size ~a loses ~a eps.
  for (int n = 1; n <= 60; n += 3) {
    for (double f : {0.05, 0.5, 0.9, 1.0, 1.1, 1.5, 2.0, 3.0}) {
      const double x = f * n + (f > 1.0 ? 2.0 : 0.0);
      const double q = q_integer(n, x);
      EXPECT_NEAR(regularized_gamma_q(n, x) / q, 1.0, 1e-11) << "n " << n << " x " << x;
      EXPECT_NEAR(regularized_gamma_p(n, x), 1.0 - q, 1e-13) << "n " << n << " x " << x;
      const double qh = q_half_integer(n, x);
      EXPECT_NEAR(regularized_gamma_q(n + 0.5, x) / qh, 1.0, 1e-11) << "n+1/2 " << n << " x " << x;
    }
  }
  // Far tail: Q(10, 200) = e^{-200} sum_{k<10} 200^k/k! ~ 5e-70, kept to full relative accuracy.
  EXPECT_NEAR(regularized_gamma_q(10.0, 200.0) / q_integer(10, 200.0), 1.0, 1e-12);
}

TEST(DistributionsChiSquare, KnownQuantilesAndTails) {
  // Textbook quantiles (values to 16 digits as given by SciPy 1.17 chi2.ppf; the
  // 1-dof one is also z_{0.975}^2 = 1.959963984540054^2).
  EXPECT_NEAR(chi_square_cdf(3.841458820694124, 1), 0.95, 1e-13);
  EXPECT_NEAR(chi_square_cdf(44.31410489621915, 25), 0.99, 1e-13);
  EXPECT_NEAR(chi_square_cdf(11.52397537224934, 25), 0.01, 1e-13);
  EXPECT_NEAR(chi_square_cdf(0.5, 3), 0.08110858834532418, 1e-14);
  // Upper tails (p-values) keep their relative accuracy: SciPy chi2.sf.
  EXPECT_NEAR(chi_square_sf(100.0, 25) / 6.274266201376244e-11, 1.0, 1e-10);
  EXPECT_NEAR(chi_square_sf(300.0, 20) / 8.082849629775851e-52, 1.0, 1e-10);
  // 1 dof: P(X > z^2) = P(|Z| > z) = erfc(z / sqrt 2).
  for (double z : {0.1, 1.0, 2.575829303548901, 6.0})
    EXPECT_NEAR(chi_square_sf(z * z, 1) / std::erfc(z / std::numbers::sqrt2), 1.0, 1e-12) << z;
  // 2 dof: exponential with mean 2.
  for (double x : {0.01, 1.0, 7.0, 50.0}) EXPECT_NEAR(chi_square_sf(x, 2) / std::exp(-x / 2), 1.0, 1e-13) << x;
  for (double x : {0.2, 5.0, 40.0}) EXPECT_NEAR(chi_square_cdf(x, 17) + chi_square_sf(x, 17), 1.0, 1e-14);
}

TEST(DistributionsChiSquare, BadArgumentsThrow) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(regularized_gamma_p(0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(regularized_gamma_p(-1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(regularized_gamma_q(1.0, -1.0), std::invalid_argument);
  EXPECT_THROW(regularized_gamma_q(1.0, nan), std::invalid_argument);
  EXPECT_THROW(regularized_gamma_p(nan, 1.0), std::invalid_argument);
  EXPECT_THROW(chi_square_cdf(1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(chi_square_sf(-0.5, 3.0), std::invalid_argument);
}

// ---- the incomplete beta function, the Beta and F distributions ---------------------

TEST(DistributionsBetaF, KnownValuesAndQuantiles) {
  // I_{1/2}(2, 3) = 1 - (C(4,0) + C(4,1)) / 16 = 11/16 (binomial identity).
  EXPECT_NEAR(regularized_beta(2.0, 3.0, 0.5), 11.0 / 16.0, 1e-13);
  // I_x(1, b) = 1 - (1 - x)^b.
  EXPECT_NEAR(regularized_beta(1.0, 7.5, 0.2), 1.0 - std::pow(0.8, 7.5), 1e-13);
  // Table values: F_{0.95}(5, 10) = 3.3258, t_{0.995}(30)^2 = 2.7500^2 = 7.5625.
  EXPECT_NEAR(f_upper_quantile(0.05, 5.0, 10.0), 3.3258, 2e-4);
  EXPECT_NEAR(f_upper_quantile(0.01, 1.0, 30.0), 2.7500 * 2.7500, 2e-3);
  EXPECT_NEAR(f_sf(3.3258, 5.0, 10.0), 0.05, 1e-5);
  // Large denominator degrees of freedom: F(1, inf) = chi2(1), 3.8415 at 5 %.
  EXPECT_NEAR(f_upper_quantile(0.05, 1.0, 1e6), 3.8415, 2e-3);
  // Beta(m, b) upper quantile against the closed form for m = 1.
  const double c = beta_upper_quantile(1e-5, 1.0, 16.0);
  EXPECT_NEAR(std::pow(1.0 - c, 16.0), 1e-5, 1e-12);
  const double c2 = beta_upper_quantile(1e-3, 2.0, 12.5);
  EXPECT_NEAR(regularized_beta(12.5, 2.0, 1.0 - c2), 1e-3, 1e-9);
}

TEST(DistributionsBetaF, SymmetryAndBadArguments) {
  // I_x(a, b) = 1 - I_{1-x}(b, a), across the switch point (a+1)/(a+b+2).
  for (double x : {0.05, 0.3, 0.6, 0.95})
    EXPECT_NEAR(regularized_beta(3.5, 2.0, x) + regularized_beta(2.0, 3.5, 1.0 - x), 1.0, 1e-14) << x;
  EXPECT_EQ(regularized_beta(2.0, 3.0, 0.0), 0.0);
  EXPECT_EQ(regularized_beta(2.0, 3.0, 1.0), 1.0);
  EXPECT_EQ(f_sf(std::numeric_limits<double>::infinity(), 2.0, 3.0), 0.0);
  // F(d1, d2) upper quantile and survival function are inverse to each other.
  for (double p : {0.2, 0.01, 1e-6}) EXPECT_NEAR(f_sf(f_upper_quantile(p, 4.0, 17.0), 4.0, 17.0) / p, 1.0, 1e-8) << p;
  EXPECT_THROW(regularized_beta(0.0, 1.0, 0.5), std::invalid_argument);
  EXPECT_THROW(regularized_beta(1.0, 1.0, 1.5), std::invalid_argument);
  EXPECT_THROW(beta_upper_quantile(1.0, 1.0, 2.0), std::invalid_argument);
  EXPECT_THROW(f_sf(-1.0, 1.0, 2.0), std::invalid_argument);
  EXPECT_THROW(f_sf(1.0, 0.0, 2.0), std::invalid_argument);
}

// ---- digamma and trigamma ----------------------------------------------------------

TEST(DistributionsDigamma, KnownValuesAndRecurrence) {
  // psi(1) = -gamma_Euler, psi(1/2) = -gamma_Euler - 2 ln 2 (A&S 6.3.2, 6.3.3);
  // psi'(1) = pi^2 / 6, psi'(1/2) = pi^2 / 2 (A&S 6.4.2, 6.4.4). The series is cut
  // after its z^-6 (z^-7) term at z >= 6: the first omitted terms, 1/(240 z^8) and
  // 1/(30 z^9), are 2.5e-9 and 3.3e-9 at z = 6, the accuracy tested here.
  const double euler = 0.57721566490153286;
  EXPECT_NEAR(digamma_minus_log(1.0), -euler, 4e-9);
  EXPECT_NEAR(digamma_minus_log(0.5) + std::log(0.5), -euler - 2.0 * std::numbers::ln2, 4e-9);
  EXPECT_NEAR(trigamma(1.0), std::numbers::pi * std::numbers::pi / 6.0, 4e-9);
  EXPECT_NEAR(trigamma(0.5), std::numbers::pi * std::numbers::pi / 2.0, 4e-9);
  // psi(x + 1) = psi(x) + 1/x and psi'(x + 1) = psi'(x) - 1/x^2, across the
  // switch from recurrence to series at x = 6 (both sides carry the truncation
  // error of the series at the z they end on).
  for (double x : {0.3, 2.7, 5.5, 9.0, 40.0}) {
    const double psi = digamma_minus_log(x) + std::log(x), psi1 = digamma_minus_log(x + 1.0) + std::log(x + 1.0);
    EXPECT_NEAR(psi1 - psi, 1.0 / x, 8e-9) << x;
    EXPECT_NEAR(trigamma(x + 1.0) - trigamma(x), -1.0 / (x * x), 8e-9) << x;
  }
  // Large x: psi(x) - ln x = -1/(2x) - 1/(12 x^2) + O(x^-4), psi'(x) = 1/x + 1/(2 x^2)
  // + 1/(6 x^3) + O(x^-5).
  EXPECT_NEAR(digamma_minus_log(1e4), -0.5e-4 - 1.0 / 12.0 * 1e-8, 1e-18);
  EXPECT_NEAR(trigamma(1e4), 1e-4 + 0.5e-8 + 1.0 / 6.0 * 1e-12, 1e-18);
}

// ---- Tracy-Widom and the largest canonical correlation -----------------------------

TEST(DistributionsTracyWidom, QuantilesOfTheLaw) {
  // TW1 quantiles from the law itself (C. A. Tracy, H. Widom, Commun. Math. Phys.
  // 177 (1996); tabulated e.g. by Bejan 2005 and Bornemann 2010): F1(0.4501) = 0.90,
  // F1(0.9793) = 0.95, F1(2.0234) = 0.99. The gamma approximation is stated within
  // 0.01 of them in the right tail; a wrong moment or a swapped parameter moves
  // them by 0.1 or more.
  EXPECT_NEAR(sysid::tracy_widom1_upper_quantile(0.10), 0.4501, 0.02);
  EXPECT_NEAR(sysid::tracy_widom1_upper_quantile(0.05), 0.9793, 0.02);
  EXPECT_NEAR(sysid::tracy_widom1_upper_quantile(0.01), 2.0234, 0.02);
  EXPECT_GT(sysid::tracy_widom1_upper_quantile(1e-3), sysid::tracy_widom1_upper_quantile(1e-2));
  EXPECT_THROW(sysid::tracy_widom1_upper_quantile(0.0), std::invalid_argument);
  EXPECT_THROW(sysid::tracy_widom1_upper_quantile(1.0), std::invalid_argument);
}

TEST(DistributionsTracyWidom, LargestCanonicalCorrelationHasItsStatedLevel) {
  // 400 pairs of independent Gaussian sets (6 and 10 variables, 300 samples): the
  // largest squared sample canonical correlation exceeds the 5 % quantile in
  // binomial(400, 0.05) cases, mean 20; outside 8..34 has probability below 1e-3
  // if the level holds (Johnstone reports the approximation good at such sizes).
  const double c = sysid::largest_canonical_correlation_upper_quantile(0.05, 6, 10, 300);
  int above = 0;
  for (std::uint64_t trial = 0; trial < 400; ++trial) {
    const Eigen::MatrixXd x = sysid::test::white_noise(300, 6, 7000 + trial);
    const Eigen::MatrixXd y = sysid::test::white_noise(300, 10, 9000 + trial);
    const double r1 = sysid::test::canonical_correlations(x, y)(0);
    if (r1 * r1 > c) ++above;
  }
  EXPECT_GE(above, 8);
  EXPECT_LE(above, 34);
}

TEST(DistributionsTracyWidom, LargestCanonicalCorrelationTendsToWachtersEdge) {
  // Dimensions in proportion to the samples: the quantile approaches Wachter's
  // edge (sqrt(c1 (1 - c2)) + sqrt(c2 (1 - c1)))^2 at the rate N^(-2/3).
  const double c1 = 0.03, c2 = 0.035;
  const double edge = std::pow(std::sqrt(c1 * (1 - c2)) + std::sqrt(c2 * (1 - c1)), 2);
  double previous = 1.0;
  for (double n : {1e4, 1e5, 1e6}) {
    const double c = sysid::largest_canonical_correlation_upper_quantile(1e-3, c1 * n, c2 * n, n);
    EXPECT_GT(c, edge);
    EXPECT_LT(c - edge, previous);
    previous = c - edge;
  }
  EXPECT_LT(previous, 1e-3);
  // Sets nearly as large as the samples: nearly any correlation occurs by chance.
  EXPECT_GT(sysid::largest_canonical_correlation_upper_quantile(0.01, 450, 500, 960), 0.9);
  EXPECT_THROW(sysid::largest_canonical_correlation_upper_quantile(0.01, 4, 6, 10), std::invalid_argument);
}

}  // namespace test_unit_core_distributions
