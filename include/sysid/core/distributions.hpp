#pragma once
/// @file
/// Purpose: the statistical distributions and special functions behind every test
/// and confidence bound in the library, in one place: the standard normal and
/// chi-square quantiles (spectral confidence bounds, the residual and coherence
/// tests), the regularized incomplete gamma function and the chi-square CDF and
/// survival function (the Ljung-Box and Bartlett p-values), the regularized
/// incomplete beta function with the Beta and F upper quantiles and the F survival
/// function (the F tests of diagnose's mismatch location), and the digamma and
/// trigamma functions (the bias and variance of a log-chi-square variable), and the
/// Tracy-Widom law with the largest canonical correlation of independent sets (the
/// noise level of subspace identification's order test).
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
/// - incomplete gamma: power series (Abramowitz & Stegun 6.5.29) below x = a + 1,
///   Legendre's continued fraction (A&S 6.5.31) by the modified Lentz method above
///   (src/core/distributions.cpp);
/// - incomplete beta: A&S 26.5.8 continued fraction by the modified Lentz method,
///   with the symmetry I_x(a, b) = 1 - I_{1-x}(b, a) beyond its fast side;
/// - digamma, trigamma: upward recurrence to x >= 6, then the asymptotic series
///   (A&S 6.3.18, 6.4.12).
///
/// The bodies are compiled once, in src/core/distributions.cpp.

namespace sysid {

// ---------------------------------------------------------------------------
// The normal and chi-square quantiles
// ---------------------------------------------------------------------------

/// Standard normal quantile z with P(Z <= z) = p. Preconditions: 0 < p < 1.
double normal_quantile(double p);

/// Chi-square quantile chi2_p(nu) (Wilson-Hilferty). Preconditions: 0 < p < 1, nu > 0.
double chi_square_quantile(double p, double nu);

// ---------------------------------------------------------------------------
// The incomplete gamma function and the chi-square distribution
// ---------------------------------------------------------------------------

/// Purpose: the regularized lower incomplete gamma function
///   P(a, x) = gamma(a, x) / Gamma(a) = (1/Gamma(a)) int_0^x t^{a-1} e^{-t} dt.
/// Method: power series for x < a + 1, 1 - continued fraction otherwise (see the
/// detail functions in src/core/distributions.cpp; the split is where both converge
/// fast and the one computed directly is the smaller of P and Q, so neither loses
/// digits to 1 - (~1)).
/// Preconditions: 0 < a < inf, x >= 0 (x = +inf gives 1); std::invalid_argument.
/// Numerical aspects: relative accuracy ~1e-14 for a up to ~1e3 (the prefactor
/// exp(a ln x - x - lnGamma(a)) loses ~|a ln x| eps); O(sqrt(a) + 1) work.
double regularized_gamma_p(double a, double x);

/// Purpose: the regularized upper incomplete gamma function Q(a, x) = 1 - P(a, x),
/// computed directly in its tail (x >= a + 1), so tiny upper tails (p-values such
/// as 1e-30) keep their relative accuracy. Preconditions as regularized_gamma_p.
double regularized_gamma_q(double a, double x);

/// Chi-square CDF with `dof` degrees of freedom: P(X <= x) = P(dof/2, x/2).
/// Preconditions: dof > 0, x >= 0 (std::invalid_argument).
double chi_square_cdf(double x, double dof);

/// Chi-square survival function (upper tail, the p-value of a statistic x):
/// P(X > x) = Q(dof/2, x/2). Preconditions as chi_square_cdf.
double chi_square_sf(double x, double dof);

// ---------------------------------------------------------------------------
// The incomplete beta function, the Beta and F distributions
// ---------------------------------------------------------------------------

/// Regularised incomplete beta function I_x(a, b) (A&S 26.5.8 continued fraction,
/// modified Lentz; the symmetry I_x(a, b) = 1 - I_{1-x}(b, a) for x > (a+1)/(a+b+2)).
/// Preconditions: a, b > 0, 0 <= x <= 1.
double regularized_beta(double a, double b, double x);
/// c with P(Beta(a, b) > c) = p (bisection on I_c). Preconditions: 0 < p < 1, a, b > 0.
double beta_upper_quantile(double p, double a, double b);
/// x with P(F(d1, d2) > x) = p. Preconditions: 0 < p < 1, d1, d2 > 0.
double f_upper_quantile(double p, double d1, double d2);
/// P(F(d1, d2) > x). Preconditions: d1, d2 > 0; x >= 0.
double f_sf(double x, double d1, double d2);

// ---------------------------------------------------------------------------
// Digamma and trigamma
// ---------------------------------------------------------------------------

/// psi(x) - ln x and psi'(x) (digamma, trigamma) by the upward recurrence to x >= 6
/// and their asymptotic series (A&S 6.3.18, 6.4.12), cut after the z^-6 (z^-7) term:
/// absolute error below ~4e-9 (the first omitted terms, 1/(240 z^8) and 1/(30 z^9),
/// at z = 6; tests/unit/core_distributions.cpp). E ln(chi2_nu / nu)
/// = psi(nu/2) - ln(nu/2) and Var ln(chi2_nu) = psi'(nu/2). Precondition: x > 0 (not
/// checked).
double digamma_minus_log(double x);
double trigamma(double x);

// ---------------------------------------------------------------------------
// Tracy-Widom (beta = 1) and the largest canonical correlation
// ---------------------------------------------------------------------------

/// x with P(W > x) = p for W of the Tracy-Widom law of order 1 (the real case).
/// Method: the shifted gamma with the law's first three moments (mean -1.2065336,
/// variance 1.6077810, skewness 0.2934645; F. Bornemann, "On the numerical
/// evaluation of distributions in random matrix theory", Markov Processes Relat.
/// Fields 16 (2010)); M. Chiani, "Distribution of the largest eigenvalue for real
/// Wishart and Gaussian random matrices and a simple approximation for the
/// Tracy-Widom distribution", J. Multivariate Anal. 129 (2014) 69-81, shows it is
/// within 0.01 of the law's quantiles over the right tail used here.
/// Preconditions: 0 < p < 1 (std::invalid_argument).
double tracy_widom1_upper_quantile(double p);

/// c with P(r_1^2 > c) ~ p, where r_1 is the largest sample canonical correlation
/// between a p_vars- and a q_vars-dimensional set of independent Gaussian
/// variables observed `samples` times (the level of Roy's largest-root test).
/// Method: r_1^2 is the largest root of the Jacobi ensemble with p_vars variables,
/// hypothesis dof n = q_vars and error dof m = samples - q_vars, whose logit is
/// near mu + sigma W with W Tracy-Widom (order 1) (I. M. Johnstone, "Multivariate
/// analysis and Jacobi ensembles: largest eigenvalue, Tracy-Widom limits and rates
/// of convergence", Ann. Statist. 36 (2008) 2638-2716, Theorem 1):
///   sin^2(gamma/2) = (min(n, p) - 1/2) / (m + n - 1),
///   sin^2(phi/2)   = (max(n, p) - 1/2) / (m + n - 1),
///   mu = 2 log tan((phi + gamma)/2),
///   sigma^3 = 16 / (m + n - 1)^2 / (sin^2(phi + gamma) sin(phi) sin(gamma)).
/// As samples grow with the dimensions in proportion, c tends to Wachter's edge
/// (sqrt(c1 (1 - c2)) + sqrt(c2 (1 - c1)))^2, c1 = p_vars / samples,
/// c2 = q_vars / samples. Johnstone reports the approximation good for dimensions
/// as small as 2 to 5.
/// Preconditions: 0 < p < 1, p_vars >= 1, q_vars >= 1, samples > p_vars + q_vars
/// (std::invalid_argument).
double largest_canonical_correlation_upper_quantile(double p, double p_vars, double q_vars, double samples);

/// The centre mu and scale sigma of that approximation: logit(r_1^2) ~ mu + sigma W.
/// Preconditions as largest_canonical_correlation_upper_quantile, without p.
struct LogitTracyWidomLaw {
  double mu = 0, sigma = 0;
};
LogitTracyWidomLaw largest_canonical_correlation_law(double p_vars, double q_vars, double samples);

}  // namespace sysid
