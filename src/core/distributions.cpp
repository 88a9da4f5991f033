// Implementation of core/distributions.hpp (methods and references in the header).
#include <sysid/core/distributions.hpp>

#include <sysid/core/errors.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace sysid {

// ---------------------------------------------------------------------------
// The normal and chi-square quantiles
// ---------------------------------------------------------------------------

double normal_quantile(double p) {
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

double chi_square_quantile(double p, double nu) {
  if (!(nu > 0.0) || !std::isfinite(nu)) throw std::invalid_argument("chi_square_quantile: need 0 < nu < infinity");
  const double z = normal_quantile(p);
  const double c = 2.0 / (9.0 * nu);
  const double base = 1.0 - c + z * std::sqrt(c);
  // For tiny nu and small p the cube root base can go negative; the quantile is then ~0.
  return base > 0.0 ? nu * base * base * base : 0.0;
}

// ---------------------------------------------------------------------------
// The incomplete gamma function and the chi-square distribution
// ---------------------------------------------------------------------------

namespace detail {

/// exp(-x + a ln x - lnGamma(a)): the common prefactor of the series and the
/// continued fraction (computed in logs: x^a and Gamma(a) overflow separately
/// long before their ratio does).
double gamma_prefactor(double a, double x) { return std::exp(-x + a * std::log(x) - std::lgamma(a)); }

/// P(a, x) by its power series (Abramowitz & Stegun 6.5.29):
///   gamma(a, x) = e^{-x} x^a sum_{n>=0} x^n / (a (a+1) ... (a+n)).
/// Used for x < a + 1, where the term ratio x / (a + n) < 1 from n = 1 on, so the
/// sum converges geometrically and every term is positive (no cancellation).
double gamma_p_series(double a, double x) {
  double term = 1.0 / a, sum = term;
  for (int n = 1; n < 100000; ++n) {
    term *= x / (a + n);
    sum += term;
    if (term < sum * std::numeric_limits<double>::epsilon()) return sum * gamma_prefactor(a, x);
  }
  throw NumericalError("regularized_gamma_p: the series did not converge (a = " + std::to_string(a) +
                       ", x = " + std::to_string(x) + ")");
}

/// Q(a, x) by Legendre's continued fraction (A&S 6.5.31, in the even form
///   Gamma(a, x) = e^{-x} x^a (1/(x+1-a-) 1(1-a)/(x+3-a-) 2(2-a)/(x+5-a-) ...)),
/// evaluated forward by the modified Lentz method (Lentz, Appl. Opt. 15 (1976)
/// 668; Thompson & Barnett, J. Comput. Phys. 64 (1986) 490): every convergent is
/// available without back-substitution, and zero denominators are nudged to
/// `tiny`. Used for x >= a + 1, where it converges in O(sqrt(a)) steps.
double gamma_q_continued_fraction(double a, double x) {
  constexpr double tiny = 1e-300;
  const double eps = std::numeric_limits<double>::epsilon();
  double b = x + 1.0 - a;
  double c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < eps) return h * gamma_prefactor(a, x);
  }
  throw NumericalError("regularized_gamma_q: the continued fraction did not converge (a = " + std::to_string(a) +
                       ", x = " + std::to_string(x) + ")");
}

void check_gamma_args(double a, double x, const char* who) {
  if (!(a > 0.0) || !std::isfinite(a)) throw std::invalid_argument(std::string(who) + ": need 0 < a < infinity");
  if (!(x >= 0.0)) throw std::invalid_argument(std::string(who) + ": need x >= 0");
}

}  // namespace detail

double regularized_gamma_p(double a, double x) {
  detail::check_gamma_args(a, x, "regularized_gamma_p");
  if (x == 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  return x < a + 1.0 ? detail::gamma_p_series(a, x) : 1.0 - detail::gamma_q_continued_fraction(a, x);
}

double regularized_gamma_q(double a, double x) {
  detail::check_gamma_args(a, x, "regularized_gamma_q");
  if (x == 0.0) return 1.0;
  if (std::isinf(x)) return 0.0;
  return x < a + 1.0 ? 1.0 - detail::gamma_p_series(a, x) : detail::gamma_q_continued_fraction(a, x);
}

double chi_square_cdf(double x, double dof) {
  if (!(dof > 0.0) || !std::isfinite(dof)) throw std::invalid_argument("chi_square_cdf: need 0 < dof < infinity");
  if (!(x >= 0.0)) throw std::invalid_argument("chi_square_cdf: need x >= 0");
  return regularized_gamma_p(0.5 * dof, 0.5 * x);
}

double chi_square_sf(double x, double dof) {
  if (!(dof > 0.0) || !std::isfinite(dof)) throw std::invalid_argument("chi_square_sf: need 0 < dof < infinity");
  if (!(x >= 0.0)) throw std::invalid_argument("chi_square_sf: need x >= 0");
  return regularized_gamma_q(0.5 * dof, 0.5 * x);
}

// ---------------------------------------------------------------------------
// Beta and F distributions
// ---------------------------------------------------------------------------

double regularized_beta(double a, double b, double x) {
  if (!(a > 0.0) || !(b > 0.0) || !std::isfinite(a) || !std::isfinite(b))
    throw std::invalid_argument("regularized_beta: need 0 < a, b < infinity");
  if (!(x >= 0.0 && x <= 1.0)) throw std::invalid_argument("regularized_beta: need 0 <= x <= 1");
  if (x == 0.0) return 0.0;
  if (x == 1.0) return 1.0;
  // The continued fraction converges fast for x < (a+1)/(a+b+2); beyond, the
  // symmetric tail is computed directly (and then 1 - x is on the fast side).
  if (x > (a + 1.0) / (a + b + 2.0)) return 1.0 - regularized_beta(b, a, 1.0 - x);
  const double log_front = a * std::log(x) + b * std::log1p(-x) - (std::lgamma(a) + std::lgamma(b) - std::lgamma(a + b));
  const double front = std::exp(log_front) / a;
  // I_x = front / (1 + d1 / (1 + d2 / (1 + ...))) (A&S 26.5.8), evaluated forward by
  // the modified Lentz method with numerators 1, d1, d2, ... and denominators 1.
  constexpr double tiny = 1e-300;
  const double eps = std::numeric_limits<double>::epsilon();
  double f = tiny, C = tiny, D = 0.0;
  for (int j = 1; j < 200000; ++j) {
    double num;
    if (j == 1) {
      num = 1.0;
    } else {
      const int i = j - 1;  // index of d_i
      if (i % 2 == 1) {
        const double k = (i - 1) / 2;
        num = -(a + k) * (a + b + k) * x / ((a + 2.0 * k) * (a + 2.0 * k + 1.0));
      } else {
        const double k = i / 2;
        num = k * (b - k) * x / ((a + 2.0 * k - 1.0) * (a + 2.0 * k));
      }
    }
    D = 1.0 + num * D;
    if (std::abs(D) < tiny) D = tiny;
    C = 1.0 + num / C;
    if (std::abs(C) < tiny) C = tiny;
    D = 1.0 / D;
    const double delta = C * D;
    f *= delta;
    if (j > 1 && std::abs(delta - 1.0) < 4.0 * eps) return front * f;
  }
  throw std::runtime_error("regularized_beta: continued fraction did not converge (a = " + std::to_string(a) +
                           ", b = " + std::to_string(b) + ", x = " + std::to_string(x) + ")");
}

double beta_upper_quantile(double p, double a, double b) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("beta_upper_quantile: need 0 < p < 1");
  if (!(a > 0.0) || !(b > 0.0)) throw std::invalid_argument("beta_upper_quantile: need a, b > 0");
  if (a == 1.0) return 1.0 - std::pow(p, 1.0 / b);  // P(Beta(1, b) > c) = (1 - c)^b
  // P(Beta(a, b) > c) = I_{1-c}(b, a), computed in the tail (no 1 - (~1) cancellation);
  // it decreases in c, so bisection cannot fail.
  double lo = 0.0, hi = 1.0;
  for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
    const double mid = 0.5 * (lo + hi);
    (regularized_beta(b, a, 1.0 - mid) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double f_sf(double x, double d1, double d2) {
  if (!(d1 > 0.0) || !(d2 > 0.0)) throw std::invalid_argument("f_sf: need d1, d2 > 0");
  if (!(x >= 0.0)) throw std::invalid_argument("f_sf: need x >= 0");
  if (std::isinf(x)) return 0.0;
  // d1 X / (d1 X + d2) ~ Beta(d1/2, d2/2); its upper tail is I_{d2/(d2 + d1 x)}(d2/2, d1/2).
  return regularized_beta(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * x));
}

double f_upper_quantile(double p, double d1, double d2) {
  const double c = beta_upper_quantile(p, 0.5 * d1, 0.5 * d2);
  return c >= 1.0 ? std::numeric_limits<double>::infinity() : (d2 / d1) * c / (1.0 - c);
}

// ---------------------------------------------------------------------------
// Digamma and trigamma
// ---------------------------------------------------------------------------

double digamma_minus_log(double x) {
  double acc = 0.0, z = x;
  while (z < 6.0) {
    acc -= 1.0 / z;
    z += 1.0;
  }
  const double z2 = 1.0 / (z * z);
  return acc + std::log(z / x) - 0.5 / z - z2 * (1.0 / 12.0 - z2 * (1.0 / 120.0 - z2 / 252.0));
}

double trigamma(double x) {
  double acc = 0.0, z = x;
  while (z < 6.0) {
    acc += 1.0 / (z * z);
    z += 1.0;
  }
  const double z2 = 1.0 / (z * z);
  return acc + 1.0 / z + 0.5 * z2 + z2 / z * (1.0 / 6.0 - z2 * (1.0 / 30.0 - z2 / 42.0));
}

// ---------------------------------------------------------------------------
// Tracy-Widom (beta = 1) and the largest canonical correlation
// ---------------------------------------------------------------------------

double tracy_widom1_upper_quantile(double p) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("tracy_widom1_upper_quantile: need 0 < p < 1");
  // The gamma law Gamma(k, theta) - shift with TW1's mean, variance and skewness
  // (header): skewness 2 / sqrt(k), variance k theta^2, mean k theta - shift.
  constexpr double mean = -1.2065335745820, variance = 1.6077810345810, skewness = 0.2934645240791;
  const double k = 4.0 / (skewness * skewness), theta = std::sqrt(variance / k), shift = k * theta - mean;
  // P(W > x) = Q(k, (x + shift) / theta), decreasing in x: bisection cannot fail.
  double lo = -shift, hi = 40.0;
  for (int it = 0; it < 200 && hi - lo > 1e-12; ++it) {
    const double mid = 0.5 * (lo + hi);
    (regularized_gamma_q(k, (mid + shift) / theta) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

LogitTracyWidomLaw largest_canonical_correlation_law(double p_vars, double q_vars, double samples) {
  if (!(p_vars >= 1.0) || !(q_vars >= 1.0) || !(samples > p_vars + q_vars))
    throw std::invalid_argument("largest canonical correlation: need p_vars, q_vars >= 1 and samples > p_vars + q_vars");
  // Johnstone (2008), Theorem 1, with n = q_vars, m = samples - q_vars.
  const double total = samples - 1.0;  // m + n - 1
  const double gamma = 2.0 * std::asin(std::sqrt((std::min(q_vars, p_vars) - 0.5) / total));
  const double phi = 2.0 * std::asin(std::sqrt((std::max(q_vars, p_vars) - 0.5) / total));
  // samples > p_vars + q_vars keeps phi + gamma below pi (their half-angle sines
  // squared sum to below 1), so the tangent is finite and positive.
  LogitTracyWidomLaw law;
  law.mu = 2.0 * std::log(std::tan(0.5 * (phi + gamma)));
  law.sigma = std::cbrt(16.0 / (total * total) / (std::pow(std::sin(phi + gamma), 2) * std::sin(phi) * std::sin(gamma)));
  return law;
}

double largest_canonical_correlation_upper_quantile(double p, double p_vars, double q_vars, double samples) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("largest_canonical_correlation_upper_quantile: need 0 < p < 1");
  const LogitTracyWidomLaw law = largest_canonical_correlation_law(p_vars, q_vars, samples);
  return 1.0 / (1.0 + std::exp(-(law.mu + law.sigma * tracy_widom1_upper_quantile(p))));
}

}  // namespace sysid
